#include "femto/memory.h"

#include <fmt/format.h>
#include <unistd.h>

namespace femto {

double physical_memory_bytes() {
    const long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && page_size > 0 ? double(pages) * double(page_size) : 0.0;
}

std::string memory_shortfall(double bytes, const std::string& what) {
    // 3/4 leaves room for the rest of the process and for the system.
    const double ram = physical_memory_bytes();
    if (!(ram > 0) || !(bytes > 0.75 * ram)) return {};
    const double gib = double(1 << 30);
    return fmt::format(
        "{} would need {:.1f} GiB, more than 3/4 of this machine's {:.1f} GiB of "
        "memory",
        what, bytes / gib, ram / gib);
}

}  // namespace femto
