// Internal string helpers for messages.
#pragma once

#include <string>
#include <vector>

#include "femto/object.h"

namespace femto::detail {

/// Edit distance (insert/delete/substitute, case-insensitive).
size_t edit_distance(const std::string& a, const std::string& b);
/// The candidate closest to `name` within a sensible distance, else "" (also for an empty
/// name, which is close to every short candidate but a typo of none).
std::string closest_match(const std::string& name, const std::vector<std::string>& candidates);
/// " (did you mean \"x\"?)" with the closest_match, else "".
std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates);
/// `noun` after "a" or "an": "an integer", "a float", "an <emitter>" (by its first letter,
/// which is right for femto's type and tag names).
std::string with_article(const std::string& noun);
/// "an <emitter>", "a <bsdf>": a kind's XML tag after its article.
std::string tag_with_article(PluginKind kind);
/// The pieces of `text` between `sep`s ("a,,b" -> "a", "", "b"; "" -> one empty piece).
std::vector<std::string> split(const std::string& text, char sep);
/// "a, b, c"
std::string join(const std::vector<std::string>& items, const std::string& sep = ", ");

}  // namespace femto::detail
