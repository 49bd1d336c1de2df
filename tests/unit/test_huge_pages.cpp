// Large arrays in huge pages (femto/memory.h): what films and cube readers zero or fill first.
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "femto/memory.h"

using namespace femto;

namespace {

// The kernel's transparent-huge-page mode: "always", "madvise" or "never" (the bracketed
// word of /sys/kernel/mm/transparent_hugepage/enabled); empty when it does not say.
std::string huge_page_mode() {
    std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const size_t open = text.find('['), close = text.find(']');
    return open == std::string::npos || close == std::string::npos
               ? std::string()
               : text.substr(open + 1, close - open - 1);
}

// /proc/self/smaps' THPeligible of the mapping that holds `address`: whether the kernel may
// back it with huge pages (-1 when the kernel does not report it).
int huge_page_eligible(const void* address) {
    const uintptr_t a = reinterpret_cast<uintptr_t>(address);
    std::ifstream in("/proc/self/smaps");
    bool inside = false;
    for (std::string line; std::getline(in, line);) {
        uintptr_t lo = 0, hi = 0;
        char dash = 0;
        std::istringstream range(line);
        if (range >> std::hex >> lo >> dash >> hi && dash == '-') {
            inside = a >= lo && a < hi;
            continue;
        }
        if (inside && line.rfind("THPeligible:", 0) == 0) return std::stoi(line.substr(12));
    }
    return -1;
}

}  // namespace

TEST(HugePages, AssignedArraysHoldTheirValues) {
    // 20 MiB of floats: filled, then grown past its capacity (the old storage given back
    // first) and filled again, as a film prepared twice would be.
    std::vector<float> cube;
    assign_in_huge_pages(cube, size_t(5) << 20, 0.f);
    EXPECT_EQ(cube.size(), size_t(5) << 20);
    EXPECT_EQ(std::accumulate(cube.begin(), cube.end(), 0.0), 0.0);
    cube[12345] = 2.5f;
    assign_in_huge_pages(cube, size_t(6) << 20, 1.f);
    EXPECT_EQ(cube.size(), size_t(6) << 20);
    EXPECT_EQ(std::accumulate(cube.begin(), cube.end(), 0.0), double(size_t(6) << 20));
    assign_in_huge_pages(cube, 10, 3.f);  // smaller: the storage stays
    EXPECT_EQ(cube.size(), 10u);
    EXPECT_EQ(cube[9], 3.f);
}

TEST(HugePages, TheKernelMayBackALargeArrayWithThem) {
    const std::string mode = huge_page_mode();
    if (mode != "madvise" && mode != "always")
        GTEST_SKIP() << "this kernel's transparent huge pages are \"" << mode
                     << "\" (/sys/kernel/mm/transparent_hugepage/enabled): nothing to check";
    std::vector<float> cube;
    assign_in_huge_pages(cube, size_t(8) << 20, 0.f);  // 32 MiB
    // A point 4 MiB in lies within the advised, 2 MiB-aligned part of the array.
    const int eligible = huge_page_eligible(cube.data() + (size_t(1) << 20));
    if (eligible < 0) GTEST_SKIP() << "this kernel's /proc/self/smaps has no THPeligible field";
    EXPECT_EQ(eligible, 1) << "in \"madvise\" mode only advised memory is eligible";
    // The same amount in an ordinary vector: eligible only when the kernel uses huge pages
    // everywhere (so in "madvise" mode this shows the test can tell the two apart).
    std::vector<float> plain(size_t(8) << 20, 0.f);
    EXPECT_EQ(huge_page_eligible(plain.data() + (size_t(1) << 20)), mode == "always" ? 1 : 0);
}
