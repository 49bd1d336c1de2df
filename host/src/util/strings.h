// Internal string helpers for messages.
#pragma once

#include <string>
#include <vector>

namespace femto::detail {

/// Edit distance (insert/delete/substitute, case-insensitive).
size_t edit_distance(const std::string& a, const std::string& b);
/// " (did you mean \"x\"?)" for the closest candidate within a sensible distance, else "".
std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates);
/// "a, b, c"
std::string join(const std::vector<std::string>& items, const std::string& sep = ", ");

}  // namespace femto::detail
