// Reading the Bonn BTF formats (femto/btf.h). The layouts follow the University of Bonn's
// btflib (its read_meta_data, read_bidir_sampling, read_ubo_bdi/dfmf/fmf): little-endian,
// matrices row-major, texel (x, y) at spatial index y + height * x in the factorized formats,
// (light l, view v) at angular index l + lights * v.
#include <Imath/half.h>

#include <cmath>
#include <cstring>

#include "btf/btf_format.h"
#include "femto/btf.h"
#include "femto/btf_prefilter.h"
#include "femto/error.h"
#include "femto/log.h"

namespace femto::btf {

namespace {

using detail::Reader;

float half_to_float(uint16_t bits) {
    Imath::half h;
    h.setBits(bits);
    return float(h);
}

// ---- the common header ---------------------------------------------------------------------

struct Signature {
    Format format;
    bool rotations;    // the header lists per-texel frame rotations
    bool extra_field;  // FMF: a header version byte; BDI: a compression byte
};

Signature read_signature(Reader& in) {
    // The longest signature is 10 bytes; shorter ones are followed by the header directly.
    struct Known {
        const char* text;
        Signature signature;
    };
    static const Known known[] = {
        {"!DFMF08FCR", {Format::Dfmf, true, false}}, {"!FMF12FCER", {Format::Fmf, true, true}},
        {"!FMF06FCR", {Format::Fmf, true, false}},   {"!FMF06FC", {Format::Fmf, false, false}},
        {"!BDIF06R2!", {Format::Bdi, true, true}},
    };
    char head[10] = {};
    const size_t n = in.peek(head, sizeof(head));
    for (const Known& k : known) {
        const size_t len = std::strlen(k.text);
        if (n >= len && std::memcmp(head, k.text, len) == 0) {
            in.skip(len, "signature");
            return k.signature;
        }
    }
    if (n >= 4 && std::memcmp(head, "!PVF", 4) == 0)
        in.fail("signature", "a PVF (per-view factorized) BTF; femto reads BDI, DFMF and FMF");
    if (n >= 5 && std::memcmp(head, "!BDIF", 5) == 0)
        in.fail("signature",
                "a BDI older than \"!BDIF06R2!\" (bzip2-compressed chunks), which "
                "femto does not read; convert it with the Bonn btflib");
    in.fail("signature",
            "not a Bonn BTF file (expected !BDIF06R2!, !DFMF08FCR, !FMF06FC, "
            "!FMF06FCR or !FMF12FCER)");
}

std::string fixed_string(Reader& in, const char* field) {
    std::string s = in.text(80, field);
    s.resize(std::strlen(s.c_str()));
    return s;
}

void read_meta(Reader& in, Header& h) {
    const uint64_t start = in.position();
    const uint32_t size = in.u32("meta data size");
    const uint32_t version = in.u32("meta data version");
    if (version < 1 || version > 4)
        in.fail("meta data version", std::to_string(version) + "; femto reads versions 1 to 4");
    h.measurement_setup = fixed_string(in, "measurement setup");
    h.image_sensor = fixed_string(in, "image sensor");
    h.light_source = fixed_string(in, "light source");
    h.ppmm = in.f32("ppmm");
    for (int c = 0; c < 3; ++c) in.f32("rgb scale factor");
    if (version > 1) h.cosine_flag = in.u32("cosine flag") != 0;
    if (version > 2) in.skip(in.u32("xml size"), "measurement xml");
    if (version > 3) {
        const uint32_t channels = in.u32("channel count");
        if (channels != 3)
            in.fail("channel count",
                    std::to_string(channels) + " channels; femto renders RGB BTFs (3 channels)");
        for (uint32_t c = 0; c < channels; ++c)
            in.skip(in.u32("channel name size"), "channel name");
    }
    if (in.position() - start != size)
        in.fail("meta data size", "says " + std::to_string(size) + " bytes but the meta data " +
                                      "holds " + std::to_string(in.position() - start));
}

Vec3 spherical_direction(Reader& in, const char* field) {
    const float theta = in.f32(field), phi = in.f32(field);
    if (!std::isfinite(theta) || !std::isfinite(phi) || theta < 0.f || theta > 0.5f * kPi + 1e-4f)
        in.fail(field,
                "an inclination of " + std::to_string(theta) +
                    " rad; directions must have finite angles with inclination in [0, pi/2]");
    const float s = std::sin(theta);
    return {s * std::cos(phi), s * std::sin(phi), std::max(0.f, std::cos(theta))};
}

void read_sampling(Reader& in, Header& h) {
    const uint32_t views = in.u32("view count");
    if (views == 0 || views > detail::kMaxDirections)
        in.fail("view count", std::to_string(views) + "; expected 1 to " +
                                  std::to_string(detail::kMaxDirections));
    for (uint32_t v = 0; v < views; ++v) {
        h.views.push_back(spherical_direction(in, "view direction"));
        const uint32_t lights = in.u32("light count");
        if (lights == 0 || lights > detail::kMaxDirections)
            in.fail("light count", std::to_string(lights) + "; expected 1 to " +
                                       std::to_string(detail::kMaxDirections));
        if (v > 0 && lights != h.lights.size())
            in.fail("light count", "view " + std::to_string(v) + " lists " +
                                       std::to_string(lights) + " lights, view 0 " +
                                       std::to_string(h.lights.size()) +
                                       "; femto needs the same lights for every view");
        in.expect(lights, 8, "light directions");
        for (uint32_t l = 0; l < lights; ++l) {
            const Vec3 d = spherical_direction(in, "light direction");
            if (v == 0) h.lights.push_back(d);
        }
    }
}

void read_extent(Reader& in, Header& h) {
    h.width = in.u32("width");
    h.height = in.u32("height");
    for (const auto& [name, value] : {std::pair{"width", h.width}, std::pair{"height", h.height}})
        if (value == 0 || value > detail::kMaxTexels)
            in.fail(name, std::to_string(value) + " texels; expected 1 to " +
                              std::to_string(detail::kMaxTexels));
}

}  // namespace

void detail::skip_rotations(Reader& in) {
    const uint32_t count = in.u32("rotation count");
    in.expect(count, 36, "rotations");
    in.skip(uint64_t(count) * 36, "rotations");
    if (count > 0)
        log_warning("BTF \"" + in.path() + "\": its " + std::to_string(count) +
                    " local frame rotations are ignored");
}

namespace {

// ---- factorized formats --------------------------------------------------------------------

/// Reads one truncated SVD: scalar size, counts, singular values, U, SxV.
Factorization read_factorization(Reader& in, uint8_t scalar_size, const std::string& field) {
    if (scalar_size != 2 && scalar_size != 4)
        in.fail(field + " scalar size", std::to_string(scalar_size) +
                                            " bytes; femto reads half (2) and float (4) matrices");
    Factorization f;
    f.components = in.u32((field + " component count").c_str());
    f.rows = in.u32((field + " rows").c_str());
    f.cols = in.u32((field + " columns").c_str());
    if (f.components == 0 || f.components > detail::kMaxComponents)
        in.fail(field + " component count", std::to_string(f.components) + "; expected 1 to " +
                                                std::to_string(detail::kMaxComponents));
    const uint64_t scalars = uint64_t(f.components) * (1 + uint64_t(f.rows) + f.cols);
    in.expect(scalars, scalar_size, (field + " matrices").c_str());
    in.skip(uint64_t(f.components) * scalar_size, "singular values");
    auto matrix = [&](uint64_t count) {
        std::vector<float> m(count);
        if (scalar_size == 4) {
            in.bytes(m.data(), count * 4, field.c_str());
        } else {
            std::vector<uint16_t> bits(count);
            in.bytes(bits.data(), count * 2, field.c_str());
            for (uint64_t i = 0; i < count; ++i) m[i] = half_to_float(bits[i]);
        }
        return m;
    };
    f.u = matrix(uint64_t(f.rows) * f.components);
    f.sxv = matrix(uint64_t(f.cols) * f.components);
    return f;
}

/// A factorization oriented as angular rows x spatial rows; `channels_in_rows` is 3 for FMF
/// (the channel varies fastest within a row index) and 1 for DFMF.
struct Oriented {
    std::vector<float> angular, spatial;  // rows x components each
    uint32_t components = 0;
};

Oriented orient(Reader& in, Factorization f, const Header& h, uint64_t channels_in_rows,
                const std::string& field) {
    const uint64_t angular = channels_in_rows * h.lights.size() * h.views.size();
    const uint64_t spatial = uint64_t(h.width) * h.height;
    Oriented o;
    o.components = f.components;
    if (f.rows == angular && f.cols == spatial) {
        o.angular = std::move(f.u);
        o.spatial = std::move(f.sxv);
    } else if (f.rows == channels_in_rows * spatial && f.cols == angular / channels_in_rows) {
        in.fail(field, "stores images column-wise (rows = texels), which femto does not read yet");
    } else {
        in.fail(field, std::to_string(f.rows) + " x " + std::to_string(f.cols) +
                           " does not match the sampling and extent (" + std::to_string(angular) +
                           " x " + std::to_string(spatial) + ")");
    }
    return o;
}

float dot_row(const std::vector<float>& a, uint64_t ra, const std::vector<float>& b, uint64_t rb,
              uint32_t k) {
    const float* x = a.data() + ra * k;
    const float* y = b.data() + rb * k;
    float sum = 0.f;
    for (uint32_t i = 0; i < k; ++i) sum += x[i] * y[i];
    return sum;
}

class DfmfData final : public Data {
public:
    DfmfData(Header h, std::array<Oriented, 3> channels)
        : Data(std::move(h)), channels_(std::move(channels)) {}
    Color value(uint32_t x, uint32_t y, uint32_t l, uint32_t v) const override {
        const uint64_t a = l + uint64_t(header_.lights.size()) * v;
        const uint64_t s = y + uint64_t(header_.height) * x;
        float raw[3];
        for (int c = 0; c < 3; ++c)
            raw[c] =
                dot_row(channels_[c].angular, a, channels_[c].spatial, s, channels_[c].components);
        return finish(raw, l);
    }
    uint32_t components() const override { return channels_[0].components; }
    const Oriented& channel(int c) const { return channels_[c]; }
    uint64_t memory_bytes() const override {
        uint64_t n = 0;
        for (const Oriented& o : channels_) n += (o.angular.size() + o.spatial.size()) * 4;
        return n;
    }

private:
    std::array<Oriented, 3> channels_;
};

class FmfData final : public Data {
public:
    FmfData(Header h, Oriented m) : Data(std::move(h)), m_(std::move(m)) {}
    Color value(uint32_t x, uint32_t y, uint32_t l, uint32_t v) const override {
        const uint64_t a = 3 * (l + uint64_t(header_.lights.size()) * v);
        const uint64_t s = y + uint64_t(header_.height) * x;
        float raw[3];
        for (int c = 0; c < 3; ++c)
            raw[c] = dot_row(m_.angular, a + c, m_.spatial, s, m_.components);
        return finish(raw, l);
    }
    uint32_t components() const override { return m_.components; }
    const Oriented& matrix() const { return m_; }
    uint64_t memory_bytes() const override { return (m_.angular.size() + m_.spatial.size()) * 4; }

private:
    Oriented m_;
};

std::shared_ptr<const Data> read_dfmf(Reader& in, Header h) {
    in.u32("component count");
    h.color_model = in.i32("color model");
    if (h.color_model != kColorRgb && h.color_model != kColorLogYuv)
        in.fail("color model", std::to_string(h.color_model) +
                                   "; femto decodes 0 (RGB) and 11 (log-luminance YUV)");
    in.skip(12 + 36, "color transformation");
    std::array<Oriented, 3> channels;
    for (int c = 0; c < 3; ++c) {
        const std::string field = "channel " + std::to_string(c);
        const uint8_t scalar = in.u8((field + " scalar size").c_str());
        channels[c] = orient(in, read_factorization(in, scalar, field), h, 1, field);
    }
    in.expect_end();
    return std::make_shared<DfmfData>(std::move(h), std::move(channels));
}

std::shared_ptr<const Data> read_fmf(Reader& in, Header h, bool versioned) {
    const uint8_t version = versioned ? in.u8("header version") : 0;
    if (version > 2) in.fail("header version", std::to_string(version) + "; femto reads 0 to 2");
    if (version >= 1) h.dynamic_range_method = in.u32("dynamic range reduction");
    if (version >= 2) {
        const uint32_t rows = in.u32("height map rows"), cols = in.u32("height map columns");
        in.expect(uint64_t(rows) * cols, 2, "height map");
        in.skip(uint64_t(rows) * cols * 2, "height map");
    }
    in.u32("component count");
    const uint8_t scalar = in.u8("scalar size");
    Oriented m = orient(in, read_factorization(in, scalar, "matrix"), h, 3, "matrix");
    in.expect_end();
    return std::make_shared<FmfData>(std::move(h), std::move(m));
}

/// Spatial factor rows from the file's order (y + height x) to Factors' (x + width y).
std::vector<float> spatial_rows(const std::vector<float>& s, const Header& h, uint32_t k) {
    std::vector<float> out(s.size());
    for (uint32_t x = 0; x < h.width; ++x)
        for (uint32_t y = 0; y < h.height; ++y)
            std::copy_n(&s[(y + size_t(h.height) * x) * k], k, &out[(x + size_t(h.width) * y) * k]);
    return out;
}

/// Angular factor rows (l + lights v) of channel c, with `stride` channels per row in the
/// source (3 for FMF) and the cosine flag divided out.
std::vector<float> angular_rows(const std::vector<float>& a, const Header& h, uint32_t k, int c,
                                int stride) {
    const size_t rows = h.lights.size() * h.views.size();
    std::vector<float> out(rows * k);
    for (size_t r = 0; r < rows; ++r) {
        const float cos_light = h.lights[r % h.lights.size()].z;
        const float scale = h.cosine_flag ? (cos_light > 0.f ? 1.f / cos_light : 0.f) : 1.f;
        for (uint32_t i = 0; i < k; ++i) out[r * k + i] = a[(r * stride + c) * k + i] * scale;
    }
    return out;
}

}  // namespace

bool linear_factors(const Data& data, Factors& out) {
    const Header& h = data.header();
    if (h.color_model != kColorRgb || h.dynamic_range_method != 0) return false;
    out.width = h.width;
    out.height = h.height;
    out.lights = uint32_t(h.lights.size());
    out.views = uint32_t(h.views.size());
    if (const auto* dfmf = dynamic_cast<const DfmfData*>(&data)) {
        out.components = 0;
        for (int c = 0; c < 3; ++c)
            out.components = std::max(out.components, dfmf->channel(c).components);
        for (int c = 0; c < 3; ++c) {
            // Channels may keep different numbers of components: pad with zeros to the largest.
            const Oriented& o = dfmf->channel(c);
            const uint32_t k = o.components, kk = out.components;
            const std::vector<float> a = angular_rows(o.angular, h, k, 0, 1);
            const std::vector<float> s = spatial_rows(o.spatial, h, k);
            out.angular[c].assign(a.size() / k * kk, 0.f);
            out.spatial[c].assign(s.size() / k * kk, 0.f);
            for (size_t r = 0; r < a.size() / k; ++r)
                std::copy_n(&a[r * k], k, &out.angular[c][r * kk]);
            for (size_t r = 0; r < s.size() / k; ++r)
                std::copy_n(&s[r * k], k, &out.spatial[c][r * kk]);
        }
        return true;
    }
    if (const auto* fmf = dynamic_cast<const FmfData*>(&data)) {
        const Oriented& m = fmf->matrix();
        out.components = m.components;
        for (int c = 0; c < 3; ++c) {
            out.angular[c] = angular_rows(m.angular, h, m.components, c, 3);
            out.spatial[c] = spatial_rows(m.spatial, h, m.components);
        }
        return true;
    }
    return false;
}

Color Data::finish(const float raw[3], uint32_t light) const {
    constexpr float kEps = 1e-5f;  // btflib's default offset of the logarithms
    float c[3] = {raw[0], raw[1], raw[2]};
    if (header_.color_model == kColorLogYuv) {
        const float y = std::exp(c[0]) - kEps;
        const float u = c[1] * (y + kEps), v = c[2] * (y + kEps);
        c[0] = y + 1.13983f * v;
        c[1] = y - 0.39465f * u - 0.5806f * v;
        c[2] = y + 2.03211f * u;
    }
    if (header_.dynamic_range_method != 0)
        for (float& x : c) x = std::exp(x) - kEps;
    Color result(c[0], c[1], c[2]);
    if (header_.cosine_flag) {
        const float cos_light = header_.lights[light].z;
        result = cos_light > 0.f ? result / cos_light : Color(0.f);
    }
    return result;
}

BilinearTexels bilinear_texels(Vec2 uv, uint32_t width, uint32_t height) {
    const double fx = double(uv.x) * width - 0.5, fy = (1.0 - double(uv.y)) * height - 0.5;
    const double x0 = std::floor(fx), y0 = std::floor(fy);
    const float tx = float(fx - x0), ty = float(fy - y0);
    auto wrap = [](double i, uint32_t n) {
        const double m = std::fmod(i, double(n));
        return uint32_t(m < 0 ? m + n : m) % n;
    };
    BilinearTexels t;
    for (int d = 0; d < 2; ++d) {
        t.x[d] = wrap(x0 + d, width);
        t.y[d] = wrap(y0 + d, height);
    }
    for (int corner = 0; corner < 4; ++corner)
        t.weight[corner] = ((corner & 1) ? tx : 1.f - tx) * ((corner >> 1) ? ty : 1.f - ty);
    return t;
}

const char* format_name(Format format) {
    switch (format) {
        case Format::Bdi:
            return "BDI";
        case Format::Dfmf:
            return "DFMF";
        case Format::Fmf:
            return "FMF";
    }
    return "?";
}

std::shared_ptr<const Data> read(const std::string& path) {
    Reader in(path);
    const Signature sig = read_signature(in);
    Header h;
    h.format = sig.format;
    read_meta(in, h);
    read_sampling(in, h);
    read_extent(in, h);
    if (sig.format == Format::Bdi) return detail::read_bdi(in, std::move(h), sig.extra_field);
    if (sig.rotations) detail::skip_rotations(in);
    if (sig.format == Format::Dfmf) return read_dfmf(in, std::move(h));
    return read_fmf(in, std::move(h), sig.extra_field);
}

}  // namespace femto::btf
