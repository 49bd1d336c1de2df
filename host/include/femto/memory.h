// femto public API: the memory femto may use. A plan to allocate more than that (a huge film,
// an unwarped cube) is refused with a message, exit code 2, before it starts: the allocation
// itself would fail late, or the kernel's OOM killer would end the process without a word.
#pragma once

#include <string>

namespace femto {

/// This machine's physical memory in bytes; 0 when the system does not say.
double physical_memory_bytes();

/// The memory this process may use in bytes: the physical memory, or a smaller limit set by
/// its control group or one of that group's ancestors (a container, a systemd MemoryMax, a
/// batch scheduler: cgroup v2's `memory.max` or v1's `memory.limit_in_bytes` under
/// /sys/fs/cgroup, along the path /proc/self/cgroup names); 0 when neither is known.
double usable_memory_bytes();

/// Empty when `bytes` fit in 3/4 of usable_memory_bytes() (or it is unknown); else a message:
/// "WHAT would need X GiB, more than 3/4 of the Y GiB of memory ...".
std::string memory_shortfall(double bytes, const std::string& what);

}  // namespace femto
