// Helpers for tests of transient renders: render a scene, write its cube with --npy and read
// it (and the variance AOV) back.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "femto/film.h"
#include "femto/host.h"
#include "femto/sensor.h"
#include "scene_util.h"

namespace femto::test {

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

// .npy version 1/2: magic, version, header length (2 or 4 bytes little-endian), a Python dict
// {'descr': '<f4', 'fortran_order': False, 'shape': (...), }, then the raw data.
inline Cube read_npy(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_GE(bytes.size(), 10u);
    EXPECT_EQ(bytes.substr(0, 6), std::string("\x93NUMPY"));
    const int major = static_cast<unsigned char>(bytes[6]);
    size_t header_len = 0, offset = 0;
    if (major == 1) {
        header_len = size_t(static_cast<unsigned char>(bytes[8])) |
                     size_t(static_cast<unsigned char>(bytes[9])) << 8;
        offset = 10;
    } else {
        for (int i = 0; i < 4; ++i)
            header_len |= size_t(static_cast<unsigned char>(bytes[8 + size_t(i)])) << (8 * i);
        offset = 12;
    }
    const std::string header = bytes.substr(offset, header_len);
    EXPECT_NE(header.find("'descr': '<f4'"), std::string::npos) << header;
    EXPECT_NE(header.find("'fortran_order': False"), std::string::npos) << header;
    const size_t open = header.find("'shape': (");
    EXPECT_NE(open, std::string::npos) << header;
    std::vector<int> shape;
    std::stringstream ss(header.substr(open + 10, header.find(')', open) - open - 10));
    std::string item;
    while (std::getline(ss, item, ','))
        if (item.find_first_not_of(' ') != std::string::npos) shape.push_back(std::stoi(item));
    EXPECT_EQ(shape.size(), 4u) << header;
    Cube cube;
    if (shape.size() != 4) return cube;
    cube.H = shape[0];
    cube.W = shape[1];
    cube.T = shape[2];
    cube.C = shape[3];
    const size_t n = size_t(cube.H) * size_t(cube.W) * size_t(cube.T) * size_t(cube.C);
    EXPECT_EQ(bytes.size(), offset + header_len + n * sizeof(float));
    cube.data.resize(n);
    std::memcpy(cube.data.data(), bytes.data() + offset + header_len, n * sizeof(float));
    return cube;
}

/// Renders with `seed`, writes the outputs with --npy and reads back OUTBASE + suffix + ".npy"
/// for every suffix ("" is the cube, "_variance" the variance AOV, ...).
inline std::vector<Cube> render_cubes(Scene& scene, uint64_t seed, const std::string& name,
                                      const std::vector<std::string>& suffixes) {
    RenderOptions opt;
    opt.seed = seed;
    const RenderStats stats = render(scene, opt);
    RenderInfo info = make_render_info(scene, opt, stats);
    info.write_npy = true;
    const auto dir = femto::test::temp_dir("cube-" + name);
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

}  // namespace femto::test
