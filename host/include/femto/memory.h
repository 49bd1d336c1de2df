// femto public API: the memory femto may use. A plan to allocate more than that (a huge film,
// an unwarped cube) is refused with a message, exit code 2, before it starts: the allocation
// itself would fail late, or the kernel's OOM killer would end the process without a word.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

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

/// Marks the whole 2 MiB pages within [p, p + bytes) for transparent huge pages
/// (madvise(MADV_HUGEPAGE)). Call it before the memory is first touched: zeroing or filling it
/// then costs one page fault per 2 MiB instead of one per 4 KiB, which for a cube of hundreds of
/// megabytes on a virtual machine was seconds (bench/README.md). Does nothing below 4 MiB, or
/// where the kernel gives no huge pages (the memory stays in ordinary pages).
void advise_huge_pages(void* p, size_t bytes);

/// v.assign(n, value), with v's storage in huge pages where the kernel has them: for arrays of
/// tens of megabytes and more (a film's cube, a cube read from a file). A vector too small for
/// n gives its storage back first, so the old and the new are never held together.
template <typename T>
void assign_in_huge_pages(std::vector<T>& v, size_t n, const T& value) {
    if (v.capacity() < n) {
        std::vector<T>().swap(v);
        v.reserve(n);
        advise_huge_pages(v.data(), n * sizeof(T));
    }
    v.assign(n, value);
}

}  // namespace femto
