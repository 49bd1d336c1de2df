// Internal: reading a container's memory limit (femto/memory.h uses it; tests check it).
#pragma once

#include <optional>
#include <string>

namespace femto::detail {

/// A control group's memory limit file's text ("max" or a byte count) as bytes; nothing when
/// it sets no limit or does not parse.
std::optional<double> parse_cgroup_limit(const std::string& text);

/// The smallest memory limit of the process's control groups and their ancestors, given the
/// text of /proc/self/cgroup and the folder the cgroup file systems are mounted under
/// (/sys/fs/cgroup): cgroup v2's memory.max along the unified group's path (when ROOT holds
/// cgroup.controllers), and v1's ROOT/memory/.../memory.limit_in_bytes along the memory
/// controller's. Nothing when no file sets a limit.
std::optional<double> cgroup_memory_limit(const std::string& proc_self_cgroup,
                                          const std::string& root);

}  // namespace femto::detail
