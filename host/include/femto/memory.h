// femto public API: the memory femto may use. A plan to allocate more than that (a huge film,
// an unwarped cube) is refused with a message, exit code 2, before it starts: the allocation
// itself would fail late, or the kernel's OOM killer would end the process without a word.
#pragma once

#include <string>

namespace femto {

/// This machine's physical memory in bytes; 0 when the system does not say.
double physical_memory_bytes();

/// The memory this process may use in bytes: the physical memory, or a container's smaller
/// limit (the control group's `memory.max`, cgroup v2, or `memory.limit_in_bytes`, v1, as
/// mounted at /sys/fs/cgroup); 0 when neither is known.
double usable_memory_bytes();

/// Empty when `bytes` fit in 3/4 of usable_memory_bytes() (or it is unknown); else a message:
/// "WHAT would need X GiB, more than 3/4 of the Y GiB of memory ...".
std::string memory_shortfall(double bytes, const std::string& what);

}  // namespace femto
