// femto public API: the machine's memory. A plan to allocate more than the machine holds
// (a huge film, an unwarped cube) is refused with a message, exit code 2, before it starts:
// the allocation itself would fail late, or the kernel's OOM killer would end the process
// without a word.
#pragma once

#include <string>

namespace femto {

/// This machine's physical memory in bytes; 0 when the system does not say.
double physical_memory_bytes();

/// Empty when `bytes` fit in 3/4 of the physical memory (or the memory is unknown); else a
/// message: "WHAT would need X GiB, more than 3/4 of this machine's Y GiB of memory".
std::string memory_shortfall(double bytes, const std::string& what);

}  // namespace femto
