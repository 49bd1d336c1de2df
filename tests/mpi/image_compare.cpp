// femto_image_compare A B REL: exits 0 when the images A and B (.exr or .npy, as femto writes
// them) agree value by value to |a - b| <= REL * max(|a|, |b|), else 1 (2 on unreadable input);
// prints the largest relative difference. Radiance totals are sums of non-negative terms, so
// rounding differences stay relative to the value itself: no absolute floor is needed. REL = 0
// asks for bit-identical values.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "femto/image_io.h"

namespace {

std::vector<float> load(const std::string& path, std::string& shape) {
    if (path.size() > 4 && path.substr(path.size() - 4) == ".npy") {
        std::vector<size_t> dims;
        std::vector<float> data = femto::io::read_npy(path, dims);
        for (size_t d : dims) shape += (shape.empty() ? "" : "x") + std::to_string(d);
        return data;
    }
    int width = 0, height = 0;
    std::vector<float> data = femto::io::read_image_rgb(path, width, height, false);
    shape = std::to_string(width) + "x" + std::to_string(height) + "x3";
    return data;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: femto_image_compare A B REL\n");
        return 2;
    }
    std::vector<float> a, b;
    std::string shape_a, shape_b;
    try {
        a = load(argv[1], shape_a);
        b = load(argv[2], shape_b);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "femto_image_compare: %s\n", e.what());
        return 2;
    }
    const double rel = std::atof(argv[3]);
    if (shape_a != shape_b) {
        std::printf("%s is %s, %s is %s\n", argv[1], shape_a.c_str(), argv[2], shape_b.c_str());
        return 1;
    }
    double worst = 0, sum_a = 0, sum_b = 0;
    size_t failures = 0, nonzero = 0, worst_at = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        const double x = a[i], y = b[i];
        sum_a += x, sum_b += y, nonzero += x != 0 ? 1 : 0;
        const double scale = std::max(std::abs(x), std::abs(y));
        if (!std::isfinite(x) || !std::isfinite(y)) {
            ++failures;
            continue;
        }
        const double d = std::abs(x - y);
        if (d > rel * scale) ++failures;
        if (scale > 0 && d / scale > worst) worst = d / scale, worst_at = i;
    }
    std::printf(
        "%s vs %s: %zu values (%zu non-zero), sums %.9g vs %.9g, largest relative "
        "difference %.3g (value %zu), %zu beyond %g\n",
        argv[1], argv[2], a.size(), nonzero, sum_a, sum_b, worst, worst_at, failures, rel);
    return failures == 0 && nonzero > 0 ? 0 : 1;
}
