// femto testing kit (installed with the SDK, target femto::testing; needs GoogleTest): render a
// scene and read its time-resolved cube back, for tests of integrators and films. The
// transient film writes OUTBASE.npy (float32 [H, W, T, C]) when asked; these helpers render,
// write into a temporary folder and read the arrays back.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "femto/film.h"
#include "femto/host.h"
#include "femto/sensor.h"
#include "femto/time.h"

namespace femto::testing {

/// A fresh, empty temporary folder per call (named after `name` and the process).
inline std::filesystem::path temp_dir(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() /
                     ("femto-test-" + name + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

/// A time-resolved cube [H, W, T, C] as the transient film writes it.
struct Cube {
    int H = 0, W = 0, T = 0, C = 0;
    std::vector<float> data;
    float at(int y, int x, int t, int c) const {
        return data[((size_t(y) * size_t(W) + size_t(x)) * size_t(T) + size_t(t)) * size_t(C) +
                    size_t(c)];
    }
    /// Sum over the colour channels of bin t.
    double energy(int y, int x, int t) const {
        double e = 0;
        for (int c = 0; c < C; ++c) e += at(y, x, t, c);
        return e;
    }
};

/// Reads a float32 C-order .npy of four dimensions (format versions 1 and 2: magic, version,
/// little-endian header length, a Python dict with descr, fortran_order and shape, the data).
inline Cube read_npy(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    Cube cube;
    EXPECT_GE(bytes.size(), 10u) << path;
    if (bytes.size() < 12 || bytes.compare(0, 6, "\x93NUMPY") != 0) {
        ADD_FAILURE() << path << " is not a .npy file";
        return cube;
    }
    const bool v1 = static_cast<unsigned char>(bytes[6]) == 1;
    const size_t offset = v1 ? 10 : 12;
    size_t header_len = 0;
    for (size_t i = 0; i < (v1 ? 2u : 4u); ++i)
        header_len |= size_t(static_cast<unsigned char>(bytes[8 + i])) << (8 * i);
    const std::string header = bytes.substr(offset, header_len);
    EXPECT_NE(header.find("'descr': '<f4'"), std::string::npos) << header;
    EXPECT_NE(header.find("'fortran_order': False"), std::string::npos) << header;
    const size_t open = header.find("'shape': (");
    std::vector<int> shape;
    if (open != std::string::npos) {
        std::stringstream ss(header.substr(open + 10, header.find(')', open) - open - 10));
        std::string item;
        while (std::getline(ss, item, ','))
            if (item.find_first_not_of(' ') != std::string::npos) shape.push_back(std::stoi(item));
    }
    if (shape.size() != 4) {
        ADD_FAILURE() << path << ": expected a 4-d array, header " << header;
        return cube;
    }
    cube.H = shape[0], cube.W = shape[1], cube.T = shape[2], cube.C = shape[3];
    const size_t n = size_t(cube.H) * size_t(cube.W) * size_t(cube.T) * size_t(cube.C);
    if (bytes.size() != offset + header_len + n * sizeof(float)) {
        ADD_FAILURE() << path << ": " << bytes.size() << " bytes do not hold the shape";
        return Cube{};
    }
    cube.data.resize(n);
    std::memcpy(cube.data.data(), bytes.data() + offset + header_len, n * sizeof(float));
    return cube;
}

/// Renders with `seed`, writes the outputs with .npy files and reads back OUTBASE + suffix +
/// ".npy" for every suffix ("" is the cube, "_variance" the variance AOV, ...).
inline std::vector<Cube> render_cubes(Scene& scene, uint64_t seed, const std::string& name,
                                      const std::vector<std::string>& suffixes) {
    RenderOptions opt;
    opt.seed = seed;
    const RenderStats stats = render(scene, opt);
    RenderInfo info = make_render_info(scene, opt, stats);
    info.write_npy = true;
    const auto dir = temp_dir("cube-" + name);
    scene.sensor().film().write((dir / name).string(), info);
    std::vector<Cube> out;
    for (const std::string& suffix : suffixes)
        out.push_back(read_npy((dir / (name + suffix + ".npy")).string()));
    std::filesystem::remove_all(dir);
    return out;
}

inline Cube render_cube(Scene& scene, uint64_t seed, const std::string& name) {
    return render_cubes(scene, seed, name, {""})[0];
}

/// The cube and its variance AOV (the scene's film needs aovs="variance"): the variance of
/// each pixel-bin estimate.
inline std::pair<Cube, Cube> render_cube_and_variance(Scene& scene, uint64_t seed,
                                                      const std::string& name) {
    std::vector<Cube> c = render_cubes(scene, seed, name, {"", "_variance"});
    return {std::move(c[0]), std::move(c[1])};
}

/// Renders with `seed` and returns the film's image integrated over time (what OUTBASE.exr
/// holds for a steady film): linear RGB, row-major.
inline std::vector<float> render_steady(Scene& scene, uint64_t seed) {
    RenderOptions opt;
    opt.seed = seed;
    render(scene, opt);
    return scene.sensor().film().steady_image();
}

/// A Monte Carlo mean and its standard error.
struct MeanAndError {
    double mean = 0, standard_error = 0;
};

/// Mean of independent estimates of the same expectation and its standard error from their
/// spread.
inline MeanAndError mean_and_error(const std::vector<double>& values) {
    const double n = double(values.size());
    double sum = 0, sum2 = 0;
    for (const double v : values) sum += v, sum2 += v * v;
    const double mean = sum / n, var = (sum2 - n * mean * mean) / (n - 1);
    return {mean, std::sqrt(std::max(0.0, var) / n)};
}

/// mean_and_error() of one channel of an RGB image's pixels (independent pixels of equal
/// expectation, e.g. a furnace).
inline MeanAndError pixel_mean(const std::vector<float>& rgb, int channel) {
    std::vector<double> values(rgb.size() / 3);
    for (size_t i = 0; i < values.size(); ++i) values[i] = rgb[3 * i + size_t(channel)];
    return mean_and_error(values);
}

/// Energy-weighted mean bin centre of a cube with window start `start` and bin width `width`,
/// counting channel `channel` (-1: all), and its standard error. It is a ratio of sums over
/// independent pixels, m = sum A_p / sum B_p (A_p = sum_t c_t E_pt, B_p = sum_t E_pt), whose
/// standard error by the delta method is sqrt(n / (n - 1) sum_p (A_p - m B_p)^2) / sum_p B_p.
inline MeanAndError mean_arrival(const Cube& cube, double start, double width, int channel = -1) {
    std::vector<double> A, B;
    double sa = 0, sb = 0;
    for (int y = 0; y < cube.H; ++y)
        for (int x = 0; x < cube.W; ++x) {
            double a = 0, b = 0;
            for (int t = 0; t < cube.T; ++t) {
                const double e = channel < 0 ? cube.energy(y, x, t) : cube.at(y, x, t, channel);
                a += (start + (t + 0.5) * width) * e;
                b += e;
            }
            A.push_back(a), B.push_back(b), sa += a, sb += b;
        }
    if (!(sb > 0)) return {};
    const double m = sa / sb;
    double r2 = 0;
    for (size_t i = 0; i < A.size(); ++i) r2 += (A[i] - m * B[i]) * (A[i] - m * B[i]);
    const double n = double(A.size());
    return {m, std::sqrt(n / (n - 1) * r2) / sb};
}

/// Expects two RGB images rendered from the same random numbers to agree up to the float
/// rounding of their accumulations (1e-4 relative, 1e-6 absolute for dark values), naming up
/// to 10 differing values; and the second not to be black (the comparison is not vacuous).
inline void expect_same_image(const std::vector<float>& a, const std::vector<float>& b,
                              const std::string& name_a, const std::string& name_b) {
    ASSERT_EQ(a.size(), b.size());
    double total = 0;
    int bad = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        total += b[i];
        const double tol = 1e-4 * std::max(std::abs(a[i]), std::abs(b[i])) + 1e-6;
        if (std::abs(double(a[i]) - b[i]) > tol && ++bad <= 10)
            ADD_FAILURE() << "value " << i << " (pixel " << i / 3 << ", channel " << i % 3
                          << "): " << name_a << " " << a[i] << ", " << name_b << " " << b[i];
    }
    EXPECT_EQ(bad, 0);
    EXPECT_GT(total, 0.0);
}

/// The bin of the window [start, start + bins * width) holding t, or -1 (as films bin).
inline int bin_of(double start, double width, int bins, double t) {
    TimeGrid grid;
    grid.start = start;
    grid.bin_width = width;
    grid.bins = bins;
    return grid.bin_of(t);
}

}  // namespace femto::testing
