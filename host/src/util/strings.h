// Internal string helpers for messages.
#pragma once

#include <string>
#include <vector>

namespace femto::detail {

/// Edit distance (insert/delete/substitute, case-insensitive).
size_t edit_distance(const std::string& a, const std::string& b);
/// The candidate closest to `name` within a sensible distance, else "" (also for an empty
/// name, which is close to every short candidate but a typo of none).
std::string closest_match(const std::string& name, const std::vector<std::string>& candidates);
/// " (did you mean \"x\"?)" with the closest_match, else "".
std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates);
/// "a, b, c"
std::string join(const std::vector<std::string>& items, const std::string& sep = ", ");

}  // namespace femto::detail
