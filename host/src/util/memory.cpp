#include "femto/memory.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>

#include "util/memory_limit.h"

namespace femto {

double physical_memory_bytes() {
    const long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && page_size > 0 ? double(pages) * double(page_size) : 0.0;
}

namespace detail {
std::optional<double> parse_cgroup_limit(const std::string& text) {
    std::istringstream in(text);
    std::string word;
    if (!(in >> word) || word.empty() || word.size() > 20) return std::nullopt;  // "max", too
    if (!std::all_of(word.begin(), word.end(), [](unsigned char c) { return std::isdigit(c); }))
        return std::nullopt;
    const double bytes = std::stod(word);
    return bytes > 0 ? std::optional<double>(bytes) : std::nullopt;
}
}  // namespace detail

namespace {
std::optional<double> cgroup_limit(const char* path) {
    std::ifstream file(path);
    if (!file) return std::nullopt;
    std::ostringstream text;
    text << file.rdbuf();
    return detail::parse_cgroup_limit(text.str());
}
}  // namespace

double usable_memory_bytes() {
    // A container's limit is what the OOM killer enforces; v1 reports "no limit" as a huge
    // count, which the minimum with the physical memory ignores.
    double bytes = physical_memory_bytes();
    for (const char* path :
         {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"})
        if (const std::optional<double> limit = cgroup_limit(path))
            bytes = bytes > 0 ? std::min(bytes, *limit) : *limit;
    return bytes;
}

std::string memory_shortfall(double bytes, const std::string& what) {
    // 3/4 leaves room for the rest of the process and for the system.
    const double ram = physical_memory_bytes(), usable = usable_memory_bytes();
    if (!(usable > 0) || !(bytes > 0.75 * usable)) return {};
    const double gib = double(1 << 30);
    const std::string whose =
        usable < ram ? "this process's memory limit (control group)" : "this machine's memory";
    return fmt::format("{} would need {:.1f} GiB, more than 3/4 of {}, {:.1f} GiB", what,
                       bytes / gib, whose, usable / gib);
}

}  // namespace femto
