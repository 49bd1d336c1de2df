// Writing the Bonn BTF formats (femto btf synth, tests): the exact inverse of btf_read.cpp and
// btf_bdi.cpp, in the layouts the Bonn btflib writes (meta data version 4, RGB channels).
#include <Imath/half.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>

#include "femto/btf.h"
#include "femto/error.h"

namespace femto::btf {

namespace {

class Writer {
public:
    explicit Writer(const std::string& path) : path_(path), out_(path, std::ios::binary) {
        if (!out_) throw SceneError("cannot write \"" + path + "\": " + std::strerror(errno));
    }
    ~Writer() = default;
    template <typename T>
    void scalar(T v) {
        out_.write(reinterpret_cast<const char*>(&v), sizeof(T));
    }
    void text(const std::string& s, size_t size) {
        std::string padded = s.substr(0, size);
        padded.resize(size, '\0');
        out_.write(padded.data(), std::streamsize(size));
    }
    void floats(const std::vector<float>& values, bool half) {
        for (float v : values) {
            if (half)
                scalar<uint16_t>(Imath::half(v).bits());
            else
                scalar<float>(v);
        }
    }
    void finish() {
        out_.close();
        if (!out_) throw SceneError("cannot write \"" + path_ + "\" (disk full?)");
    }

private:
    std::string path_;
    std::ofstream out_;
};

void write_meta(Writer& w, const Header& h) {
    const uint32_t size = 4 + 4 + 3 * 80 + 4 + 12 + 4 + 4 + 4 + 3 * (4 + 1);
    w.scalar<uint32_t>(size);
    w.scalar<uint32_t>(4);  // version: cosine flag, xml, channel names
    w.text(h.measurement_setup, 80);
    w.text(h.image_sensor, 80);
    w.text(h.light_source, 80);
    w.scalar<float>(h.ppmm);
    for (int c = 0; c < 3; ++c) w.scalar<float>(1.f);  // rgb scale factor
    w.scalar<uint32_t>(h.cosine_flag ? 1 : 0);
    w.scalar<uint32_t>(0);  // no xml
    w.scalar<uint32_t>(3);
    for (const char* name : {"R", "G", "B"}) {
        w.scalar<uint32_t>(1);
        w.text(name, 1);
    }
}

void write_direction(Writer& w, const Vec3& d) {
    w.scalar<float>(std::acos(std::clamp(d.z, -1.f, 1.f)));
    w.scalar<float>(std::atan2(d.y, d.x));
}

void write_common(Writer& w, const char* signature, const Header& h) {
    w.text(signature, std::char_traits<char>::length(signature));
    write_meta(w, h);
    w.scalar<uint32_t>(uint32_t(h.views.size()));
    for (const Vec3& v : h.views) {
        write_direction(w, v);
        w.scalar<uint32_t>(uint32_t(h.lights.size()));
        for (const Vec3& l : h.lights) write_direction(w, l);
    }
    w.scalar<uint32_t>(h.width);
    w.scalar<uint32_t>(h.height);
}

void write_factorization(Writer& w, const Factorization& f, bool half) {
    w.scalar<uint8_t>(half ? 2 : 4);
    w.scalar<uint32_t>(f.components);
    w.scalar<uint32_t>(f.rows);
    w.scalar<uint32_t>(f.cols);
    w.floats(std::vector<float>(f.components, 1.f), half);  // singular values (folded into SxV)
    w.floats(f.u, half);
    w.floats(f.sxv, half);
}

void check_factorization(const Factorization& f, uint64_t rows, uint64_t cols) {
    if (f.rows != rows || f.cols != cols || f.u.size() != uint64_t(f.rows) * f.components ||
        f.sxv.size() != uint64_t(f.cols) * f.components)
        throw std::invalid_argument("btf::write: a factorization's sizes do not match the header");
}

}  // namespace

void write_bdi(const std::string& path, const Header& h, const std::vector<float>& values) {
    const uint64_t abrdf = 3 * uint64_t(h.lights.size()) * h.views.size();
    if (values.size() != abrdf * h.width * h.height)
        throw std::invalid_argument("btf::write_bdi: values do not match the header's sizes");
    constexpr uint32_t kScanLines = 4;  // as btflib writes them
    const uint32_t scan_lines = std::min(kScanLines, h.height);
    Writer w(path);
    write_common(w, "!BDIF06R2!", h);
    w.scalar<uint32_t>(scan_lines);
    w.scalar<uint8_t>(2);  // sparse uncompressed; the mask below keeps every texel
    for (uint64_t i = 0; i < uint64_t(h.width) * h.height; ++i) w.scalar<uint8_t>(1);
    w.scalar<uint32_t>(0);  // no rotations
    const uint64_t per_chunk = uint64_t(h.width) * scan_lines;
    const uint64_t texels = uint64_t(h.width) * h.height;
    for (uint64_t first = 0; first < texels; first += per_chunk) {
        const uint64_t count = std::min(per_chunk, texels - first);
        w.scalar<uint32_t>(uint32_t(count * abrdf * 2));
        w.floats(std::vector<float>(values.begin() + int64_t(first * abrdf),
                                    values.begin() + int64_t((first + count) * abrdf)),
                 true);
    }
    w.finish();
}

void write_dfmf(const std::string& path, const Header& h,
                const std::array<Factorization, 3>& channels, bool half) {
    const uint64_t angular = uint64_t(h.lights.size()) * h.views.size();
    for (const Factorization& f : channels)
        check_factorization(f, angular, uint64_t(h.width) * h.height);
    Writer w(path);
    write_common(w, "!DFMF08FCR", h);
    w.scalar<uint32_t>(0);  // no rotations
    uint32_t components = 0;
    for (const Factorization& f : channels) components = std::max(components, f.components);
    w.scalar<uint32_t>(components);
    w.scalar<int32_t>(h.color_model);
    for (int i = 0; i < 3; ++i) w.scalar<float>(0.f);  // colour mean (PCA model only)
    for (int i = 0; i < 9; ++i) w.scalar<float>(i % 4 == 0 ? 1.f : 0.f);
    for (const Factorization& f : channels) write_factorization(w, f, half);
    w.finish();
}

void write_fmf(const std::string& path, const Header& h, const Factorization& matrix, bool half) {
    check_factorization(matrix, 3 * uint64_t(h.lights.size()) * h.views.size(),
                        uint64_t(h.width) * h.height);
    Writer w(path);
    write_common(w, "!FMF06FCR", h);
    w.scalar<uint32_t>(0);  // no rotations
    w.scalar<uint32_t>(matrix.components);
    write_factorization(w, matrix, half);
    w.finish();
}

namespace {

std::vector<Vec3> rings(const std::vector<float>& inclination_deg, const std::vector<int>& count,
                        const std::vector<float>& offset_deg) {
    std::vector<Vec3> dirs;
    for (size_t r = 0; r < inclination_deg.size(); ++r) {
        const float theta = inclination_deg[r] * kPi / 180.f;
        for (int j = 0; j < count[r]; ++j) {
            const float phi = (offset_deg[r] + 360.f * float(j) / float(count[r])) * kPi / 180.f;
            dirs.push_back({std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                            std::cos(theta)});
        }
    }
    return dirs;
}

}  // namespace

std::vector<Vec3> ubo2003_directions() {
    return rings({0, 15, 30, 45, 60, 75}, {1, 6, 12, 18, 20, 24}, {0, 0, 0, 0, 0, 0});
}

std::vector<Vec3> ubo2014_directions() {
    return rings({0, 11, 23.5f, 30, 37.5f, 45, 52.5f, 60, 67.5f, 75},
                 {1, 6, 12, 12, 12, 18, 18, 24, 24, 24}, {0, 15, 0, 15, 0, 0, 7.5f, 0, 7.5f, 0});
}

}  // namespace femto::btf
