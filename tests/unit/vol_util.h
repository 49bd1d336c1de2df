// Writing Mitsuba `gridvolume` files (.vol) for tests of the heterogeneous medium.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "femto/math.h"

namespace femto::test {

/// The contents of a .vol file, with every header field settable (to write bad files).
struct VolFile {
    std::string magic = "VOL";
    int version = 3;
    int32_t encoding = 1;
    int32_t res[3] = {1, 1, 1};
    int32_t channels = 1;
    float bbox[6] = {0, 0, 0, 1, 1, 1};
    std::vector<float> data;

    std::string bytes() const {
        std::string s = magic;
        s.push_back(static_cast<char>(version));
        auto put = [&](const void* p, size_t n) { s.append(static_cast<const char*>(p), n); };
        put(&encoding, 4);
        put(res, 12);
        put(&channels, 4);
        put(bbox, 24);
        put(data.data(), data.size() * sizeof(float));
        return s;
    }
};

inline void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// A grid of `res` with data f(x, y, z) (lattice indices) over the box [lo, hi].
template <typename F>
VolFile make_grid(int nx, int ny, int nz, Vec3 lo, Vec3 hi, const F& f) {
    VolFile v;
    v.res[0] = nx;
    v.res[1] = ny;
    v.res[2] = nz;
    const float box[6] = {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z};
    std::memcpy(v.bbox, box, sizeof(box));
    for (int z = 0; z < nz; ++z)
        for (int y = 0; y < ny; ++y)
            for (int x = 0; x < nx; ++x) v.data.push_back(static_cast<float>(f(x, y, z)));
    return v;
}

}  // namespace femto::test
