// Internal: reading a container's memory limit (femto/memory.h uses it; tests check it).
#pragma once

#include <optional>
#include <string>

namespace femto::detail {

/// A control group's memory limit file's text ("max" or a byte count) as bytes; nothing when
/// it sets no limit or does not parse.
std::optional<double> parse_cgroup_limit(const std::string& text);

}  // namespace femto::detail
