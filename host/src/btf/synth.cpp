#include "btf/synth.h"

#include <cmath>
#include <stdexcept>

#include "btf/vgroove.h"

namespace femto::btf::synth {

namespace {

// BTF A's constants (docs/btf.md). Channel means keep B >= 0.03: T_0 >= 0.25,
// |T_1| <= 0.15 and T_2 <= 0.14 with P_2 >= -1/2.
constexpr double kMean[3][3] = {{0.55, 0.45, 0.35}, {0.10, 0.12, 0.08}, {0.08, 0.06, 0.10}};
constexpr double kSwing[3] = {0.10, 0.03, 0.04};
constexpr int kFreqX[3] = {1, 2, 3}, kFreqY[3] = {2, 1, 3};
constexpr double kPhaseX[3] = {0.3, 1.1, 2.0}, kPhaseY[3] = {0.7, 0.2, 1.5};

Vec3 polar(double theta_deg, double phi_deg) {
    const double t = theta_deg * kPi / 180, p = phi_deg * kPi / 180;
    return Vec3(float(std::sin(t) * std::cos(p)), float(std::sin(t) * std::sin(p)),
                float(std::cos(t)));
}
const Vec3 kAxisA = polar(40, 30), kAxisB = polar(25, 200), kAxisC = polar(20, 120);

double dotd(const Vec3& a, const Vec3& b) {
    return double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z;
}

/// The mean of cos(w (i + 1/2) + phase) over i = i0 .. i0 + n - 1 (a Dirichlet sum).
double cosine_block_mean(double w, double phase, uint32_t i0, uint32_t n) {
    const double s = std::sin(0.5 * w);
    const double centre = w * (double(i0) + 0.5) + phase + 0.5 * (double(n) - 1) * w;
    if (std::abs(s) < 1e-12) return std::cos(centre);
    return std::sin(0.5 * double(n) * w) / (double(n) * s) * std::cos(centre);
}

double legendre2(double x) { return 0.5 * (3 * x * x - 1); }

}  // namespace

double HarmonicBtf::spatial(int c, int k, uint32_t x, uint32_t y) const {
    return spatial_box_mean(c, k, x, y, 1, 1);
}

double HarmonicBtf::spatial_box_mean(int c, int k, uint32_t x0, uint32_t y0, uint32_t nx,
                                     uint32_t ny) const {
    const double wx = 2 * kPi * kFreqX[k] / width_, wy = 2 * kPi * kFreqY[k] / height_;
    return kMean[k][c] + kSwing[k] * cosine_block_mean(wx, kPhaseX[k], x0, nx) *
                             cosine_block_mean(wy, kPhaseY[k], y0, ny);
}

double HarmonicBtf::spatial_downsampled(int c, int k, int level, uint32_t x, uint32_t y,
                                        const std::array<float, 4>& weights) const {
    auto axis = [&](double w, double phase, uint32_t i) {
        double amplitude = 1;
        for (int step = 0; step < level; ++step, w *= 2) {
            double h = 0;
            for (int t = 0; t < 4; ++t) h += weights[t] * std::cos(w * (t - 1.5));
            amplitude *= h;
        }
        return amplitude * std::cos(w * (double(i) + 0.5) + phase);
    };
    const double wx = 2 * kPi * kFreqX[k] / width_, wy = 2 * kPi * kFreqY[k] / height_;
    return kMean[k][c] + kSwing[k] * axis(wx, kPhaseX[k], x) * axis(wy, kPhaseY[k], y);
}

double HarmonicBtf::angular_filtered(int k, const Vec3& l, const Vec3& v,
                                     const std::vector<double>& light_scales,
                                     const std::vector<double>& view_scales) {
    if (k == 0) return 1;
    if (k == 1) return light_scales[1] * view_scales[1] * angular(1, l, v);
    return light_scales[2] * angular(2, l, v);
}

double HarmonicBtf::angular(int k, const Vec3& l, const Vec3& v) {
    if (k == 0) return 1;
    if (k == 1) return dotd(l, kAxisA) * dotd(v, kAxisB);
    return legendre2(dotd(l, kAxisC));
}

double HarmonicBtf::angular_cap_mean(int k, const Vec3& l, const Vec3& v, double alpha_l,
                                     double alpha_v) {
    const double cl = std::cos(alpha_l), cv = std::cos(alpha_v);
    const double band1_l = 0.5 * (1 + cl), band1_v = 0.5 * (1 + cv);
    const double band2_l = cl * 0.5 * (1 + cl);
    if (k == 0) return 1;
    if (k == 1) return band1_l * band1_v * angular(1, l, v);
    return band2_l * angular(2, l, v);
}

Color HarmonicBtf::value(uint32_t x, uint32_t y, const Vec3& l, const Vec3& v) const {
    Color result;
    for (int c = 0; c < 3; ++c) {
        double sum = 0;
        for (int k = 0; k < 3; ++k) sum += spatial(c, k, x, y) * angular(k, l, v);
        result[c] = float(sum);
    }
    return result;
}

Header header(const Options& o) {
    Header h;
    h.format = o.format;
    h.width = o.width;
    h.height = o.height;
    h.lights = o.directions;
    h.views = o.directions;
    h.cosine_flag = o.cosine_flag;
    h.color_model = o.color_model;
    h.measurement_setup = "femto btf synth";
    h.image_sensor = "none (synthetic)";
    h.light_source = "none (synthetic)";
    return h;
}

namespace {

/// BTF B's W texel values (albedo 1) for one (light, view) pair: the groove shades no view
/// below the horizon, and btf/vgroove.h needs v.z > 0.
std::vector<double> vgroove_row(const Options& o, const Vec3& l, const Vec3& v) {
    if (v.z <= 0.f) return std::vector<double>(o.width, 0.0);
    const VGroove g{o.vgroove_slope_deg * kPi / 180, 1.0};
    return vgroove_texels(g, int(o.width), l, v);
}

}  // namespace

Color reference_value(const Options& o, uint32_t x, uint32_t y, uint32_t l, uint32_t v) {
    if (o.kind == Kind::VGroove)
        return o.vgroove_albedo * float(vgroove_row(o, o.directions[l], o.directions[v])[x]);
    return HarmonicBtf(o.width, o.height).value(x, y, o.directions[l], o.directions[v]);
}

namespace {

/// What the file stores for B before the colour model: B, times cos(theta_l) with the flag.
Color stored_value(const Options& o, uint32_t x, uint32_t y, uint32_t l, uint32_t v) {
    const Color b = reference_value(o, x, y, l, v);
    return o.cosine_flag ? b * o.directions[l].z : b;
}

/// RGB to btflib's log-luminance model 11: (log(Y + eps), U / (Y + eps), V / (Y + eps)), with
/// the exact inverse of the decoder's YUV-to-RGB matrix.
void encode_log_yuv(const Color& rgb, float out[3]) {
    // Inverse of [[1, 0, 1.13983], [1, -0.39465, -0.5806], [1, 2.03211, 0]] (solved in double).
    const double m[3][3] = {{1, 0, 1.13983}, {1, -0.39465, -0.5806}, {1, 2.03211, 0}};
    const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                       m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                       m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    double inv[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const int a = (j + 1) % 3, b = (j + 2) % 3, p = (i + 1) % 3, q = (i + 2) % 3;
            inv[i][j] = (m[a][p] * m[b][q] - m[a][q] * m[b][p]) / det;
        }
    double yuv[3];
    for (int i = 0; i < 3; ++i) yuv[i] = inv[i][0] * rgb.r + inv[i][1] * rgb.g + inv[i][2] * rgb.b;
    constexpr double kEps = 1e-5;
    out[0] = float(std::log(yuv[0] + kEps));
    out[1] = float(yuv[1] / (yuv[0] + kEps));
    out[2] = float(yuv[2] / (yuv[0] + kEps));
}

void write_bdi_file(const std::string& path, const Options& o) {
    const size_t n = o.directions.size(), abrdf = 3 * n * n;
    std::vector<float> values(size_t(o.width) * o.height * abrdf);
    for (uint32_t v = 0; v < n; ++v)
        for (uint32_t l = 0; l < n; ++l) {
            const std::vector<double> row = o.kind == Kind::VGroove
                                                ? vgroove_row(o, o.directions[l], o.directions[v])
                                                : std::vector<double>();
            for (uint32_t y = 0; y < o.height; ++y)
                for (uint32_t x = 0; x < o.width; ++x) {
                    Color b = o.kind == Kind::VGroove ? o.vgroove_albedo * float(row[x])
                                                      : reference_value(o, x, y, l, v);
                    if (o.cosine_flag) b *= o.directions[l].z;
                    float* out = &values[(size_t(y) * o.width + x) * abrdf + 3 * (l + n * v)];
                    for (int c = 0; c < 3; ++c) out[c] = b[c];
                }
        }
    write_bdi(path, header(o), values);
}

/// BTF B as a DFMF of rank W per channel: U holds the columns' values (albedo 1, with the
/// cosine under the flag), SxV picks texel (x, y)'s column x and the channel's albedo.
Factorization vgroove_channel(const Options& o, int channel) {
    const uint32_t n = uint32_t(o.directions.size()), w = o.width;
    Factorization f{n * n, w * o.height, w, {}, {}};
    f.u.resize(size_t(n) * n * w);
    for (uint32_t v = 0; v < n; ++v)
        for (uint32_t l = 0; l < n; ++l) {
            const std::vector<double> row = vgroove_row(o, o.directions[l], o.directions[v]);
            for (uint32_t x = 0; x < w; ++x)
                f.u[size_t(l + n * v) * w + x] =
                    float(o.cosine_flag ? row[x] * o.directions[l].z : row[x]);
        }
    f.sxv.assign(size_t(f.cols) * w, 0.f);
    for (uint32_t x = 0; x < w; ++x)
        for (uint32_t y = 0; y < o.height; ++y)
            f.sxv[size_t(y + o.height * x) * w + x] = o.vgroove_albedo[channel];
    return f;
}

/// One channel of model 11, factorized trivially: U = the whole matrix, SxV = identity.
Factorization full_rank_channel(const Options& o, int channel) {
    const uint32_t n = uint32_t(o.directions.size()), texels = o.width * o.height;
    Factorization f{n * n, texels, texels, {}, {}};
    f.u.assign(size_t(f.rows) * texels, 0.f);
    f.sxv.assign(size_t(texels) * texels, 0.f);
    for (uint32_t x = 0; x < o.width; ++x)
        for (uint32_t y = 0; y < o.height; ++y) {
            const uint32_t s = y + o.height * x;
            f.sxv[size_t(s) * texels + s] = 1.f;
            for (uint32_t v = 0; v < n; ++v)
                for (uint32_t l = 0; l < n; ++l) {
                    float coded[3];
                    encode_log_yuv(stored_value(o, x, y, l, v), coded);
                    f.u[size_t(l + n * v) * texels + s] = coded[channel];
                }
        }
    return f;
}

/// One RGB channel of rank 3: U holds G_k (times cos theta_l with the flag), SxV holds T_ck.
Factorization rank3_channel(const Options& o, int channel) {
    const HarmonicBtf btf(o.width, o.height);
    const uint32_t n = uint32_t(o.directions.size());
    Factorization f{n * n, o.width * o.height, 3, {}, {}};
    for (uint32_t v = 0; v < n; ++v)
        for (uint32_t l = 0; l < n; ++l)
            for (int k = 0; k < 3; ++k) {
                const double g = HarmonicBtf::angular(k, o.directions[l], o.directions[v]);
                f.u.push_back(float(o.cosine_flag ? g * o.directions[l].z : g));
            }
    for (uint32_t x = 0; x < o.width; ++x)
        for (uint32_t y = 0; y < o.height; ++y)
            for (int k = 0; k < 3; ++k) f.sxv.push_back(float(btf.spatial(channel, k, x, y)));
    return f;
}

/// FMF: all channels in one matrix of rank 9 (each channel's three terms).
Factorization fmf_matrix(const Options& o) {
    std::array<Factorization, 3> ch = {rank3_channel(o, 0), rank3_channel(o, 1),
                                       rank3_channel(o, 2)};
    const uint32_t n = uint32_t(o.directions.size());
    Factorization f{3 * n * n, o.width * o.height, 9, {}, {}};
    f.u.assign(size_t(f.rows) * 9, 0.f);
    for (uint32_t a = 0; a < n * n; ++a)
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k)
                f.u[(size_t(3) * a + c) * 9 + 3 * c + k] = ch[c].u[a * 3 + k];
    for (uint32_t s = 0; s < f.cols; ++s)
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k) f.sxv.push_back(ch[c].sxv[s * 3 + k]);
    return f;
}

}  // namespace

void write(const std::string& path, const Options& o) {
    if (o.directions.empty() || o.width == 0 || o.height == 0)
        throw std::invalid_argument("btf synth: empty sampling or texture");
    if (o.color_model != kColorRgb && (o.format != Format::Dfmf || o.color_model != kColorLogYuv))
        throw std::invalid_argument("btf synth: colour model 11 is written for DFMF only");
    if (o.kind == Kind::VGroove && (o.format == Format::Fmf || o.color_model != kColorRgb))
        throw std::invalid_argument("btf synth: the V-groove BTF is written as BDI or RGB DFMF");
    switch (o.format) {
        case Format::Bdi:
            write_bdi_file(path, o);
            return;
        case Format::Fmf:
            write_fmf(path, header(o), fmf_matrix(o), o.half);
            return;
        case Format::Dfmf: {
            std::array<Factorization, 3> ch;
            for (int c = 0; c < 3; ++c)
                ch[c] = o.kind == Kind::VGroove         ? vgroove_channel(o, c)
                        : o.color_model == kColorLogYuv ? full_rank_channel(o, c)
                                                        : rank3_channel(o, c);
            write_dfmf(path, header(o), ch, o.half);
            return;
        }
    }
}

}  // namespace femto::btf::synth
