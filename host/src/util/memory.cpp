#include "femto/memory.h"

#include <fmt/format.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
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
// A file's whole text; empty when it cannot be read.
std::string read_text(const std::string& path) {
    std::ifstream file(path);
    std::ostringstream text;
    if (file) text << file.rdbuf();
    return text.str();
}

void keep_smallest(std::optional<double>& smallest, std::optional<double> limit) {
    if (limit) smallest = smallest ? std::min(*smallest, *limit) : *limit;
}

// The smallest limit in FILE of folder BASE + PATH and each of its ancestors up to BASE.
std::optional<double> smallest_up_the_tree(const std::string& base, std::string path,
                                           const char* file) {
    std::optional<double> smallest;
    for (;;) {
        keep_smallest(smallest, detail::parse_cgroup_limit(read_text(base + path + "/" + file)));
        if (path.empty() || path == "/") return smallest;
        path = path.substr(0, path.find_last_of('/'));
    }
}
}  // namespace

namespace detail {
std::optional<double> cgroup_memory_limit(const std::string& proc_self_cgroup,
                                          const std::string& root) {
    std::optional<double> smallest;
    const bool unified = std::ifstream(root + "/cgroup.controllers").good();
    std::istringstream lines(proc_self_cgroup);
    for (std::string line; std::getline(lines, line);) {  // "id:controllers:path"
        const size_t a = line.find(':'), b = line.find(':', a + 1);
        if (a == std::string::npos || b == std::string::npos) continue;
        const std::string controllers = line.substr(a + 1, b - a - 1), path = line.substr(b + 1);
        if (controllers.empty() && unified)
            keep_smallest(smallest, smallest_up_the_tree(root, path, "memory.max"));
        std::istringstream names(controllers);
        for (std::string name; std::getline(names, name, ',');)
            if (name == "memory")
                keep_smallest(smallest, smallest_up_the_tree(root + "/memory", path,
                                                             "memory.limit_in_bytes"));
    }
    return smallest;
}
}  // namespace detail

double usable_memory_bytes() {
    // A control group's limit is what the OOM killer enforces. v1 reports "no limit" as a huge
    // count, which the minimum with the physical memory ignores.
    std::optional<double> bytes =
        detail::cgroup_memory_limit(read_text("/proc/self/cgroup"), "/sys/fs/cgroup");
    if (const double ram = physical_memory_bytes(); ram > 0) keep_smallest(bytes, ram);
    return bytes.value_or(0.0);
}

std::string memory_shortfall(double bytes, const std::string& what) {
    // 3/4 leaves room for the rest of the process and for the system.
    const double ram = physical_memory_bytes(), usable = usable_memory_bytes();
    if (!(usable > 0) || !(bytes > 0.75 * usable)) return {};
    const double gib = double(1 << 30);
    const std::string whose = ram > 0 && usable >= ram
                                  ? "this machine's memory"
                                  : "this process's memory limit (control group)";
    return fmt::format("{} would need {:.1f} GiB, more than 3/4 of {}, {:.1f} GiB", what,
                       bytes / gib, whose, usable / gib);
}

// Why by hand: neither the C++ library nor glibc's malloc can ask for huge pages per
// allocation (glibc's `glibc.malloc.hugetlb` tunable is process-wide and read from the
// environment at start-up), and no allocator library in Debian that femto uses offers it.
void advise_huge_pages(void* p, size_t bytes) {
    constexpr uintptr_t kHugePage = uintptr_t(2) << 20;
    if (!p || bytes < 2 * kHugePage) return;
    const uintptr_t begin =
        (reinterpret_cast<uintptr_t>(p) + kHugePage - 1) / kHugePage * kHugePage;
    const uintptr_t end = (reinterpret_cast<uintptr_t>(p) + bytes) / kHugePage * kHugePage;
    // Only whole 2 MiB pages inside the range: the advice reaches no other object's memory.
    // It fails harmlessly where the kernel has no huge pages to give.
    if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
}

}  // namespace femto
