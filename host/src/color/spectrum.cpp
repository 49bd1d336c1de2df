#include "color/spectrum.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace femto::spectrum {
namespace {

#include "color/cie_tables.inc"

static_assert(kCieMinNm == kMinNm && kCieMaxNm == kMaxNm);

// Mitsuba 3's constants (include/mitsuba/core/spectrum.h). The y-bar normalisation is the
// integral of y-bar under the quadrature below (106.857 exactly integrated, times 999/1000),
// so that a unit spectrum has luminance 1. The D65 one is Mitsuba's for its D65 table (100 at
// 560 nm), kept as it is: it leaves a white reflectance at luminance 0.99889, not 1.
constexpr double kYNormalization = 1.0 / 106.7502593994140625;
constexpr double kD65Normalization = 100.0 / 98.99741751876255;
// Mitsuba 3 integrates with 1000 evenly spaced samples from 360 to 830 nm inclusive, each
// weighted by 470/1000 nm.
constexpr int kSteps = 1000;

double lerp_table(const double* table, double nm) {
    if (!(nm >= kMinNm && nm <= kMaxNm)) return 0;
    const double t = (nm - kMinNm) * ((kCieSamples - 1) / (kMaxNm - kMinNm));
    const int i = std::clamp(int(t), 0, kCieSamples - 2);
    const double w = t - i;
    return (1 - w) * table[i] + w * table[i + 1];
}

}  // namespace

std::array<double, 3> cie1931_xyz(double nm) {
    return {lerp_table(kCie1931X, nm), lerp_table(kCie1931Y, nm), lerp_table(kCie1931Z, nm)};
}

double cie_d65(double nm) { return lerp_table(kCieD65, nm); }

std::array<double, 3> xyz_to_linear_srgb(const std::array<double, 3>& c) {
    // The XYZ-to-linear-sRGB matrix to six decimals, as Mitsuba 3 writes it.
    return {3.240479 * c[0] - 1.537150 * c[1] - 0.498535 * c[2],
            -0.969256 * c[0] + 1.875991 * c[1] + 0.041556 * c[2],
            0.055648 * c[0] - 0.204043 * c[1] + 1.057311 * c[2]};
}

Conversion convert(const std::function<double(double)>& value, double lo, double hi, Use use) {
    Conversion out;
    for (int i = 0; i < kSteps; ++i) {
        const double nm = kMinNm + (i / double(kSteps - 1)) * (kMaxNm - kMinNm);
        if (nm < lo || nm > hi) continue;
        // Reflectances and media are seen under D65, whose XYZ maps to sRGB white.
        const double weight =
            value(nm) * (use == Use::Emission ? 1.0 : cie_d65(nm) * kD65Normalization);
        const auto cmf = cie1931_xyz(nm);
        for (int k = 0; k < 3; ++k) out.xyz[k] += cmf[k] * weight;
    }
    for (double& c : out.xyz) c *= (kMaxNm - kMinNm) / kSteps * kYNormalization;
    auto rgb = xyz_to_linear_srgb(out.xyz);
    const double upper = use == Use::Reflectance ? 1.0 : HUGE_VAL;
    for (int k = 0; k < 3; ++k) {
        const double c = std::clamp(rgb[k], 0.0, upper);
        out.clamped = out.clamped || c != rgb[k];
        out.rgb[k] = float(c);
    }
    return out;
}

Conversion convert_sampled(const std::vector<double>& nm, const std::vector<double>& values,
                           Use use) {
    auto value = [&](double x) {
        // The sample interval holding x (the last one for x at the last sample).
        const size_t i = std::min<size_t>(
            size_t(std::upper_bound(nm.begin(), nm.end(), x) - nm.begin()), nm.size() - 1);
        const size_t j = i == 0 ? 0 : i - 1;
        const double t = (x - nm[j]) / (nm[j + 1] - nm[j]);
        return (1 - t) * values[j] + t * values[j + 1];
    };
    return convert(value, nm.front(), nm.back(), use);
}

Color convert_uniform(double v, Use use) {
    if (use != Use::Emission) return Color(float(v));
    const auto w = xyz_to_linear_srgb({1, 1, 1});
    return Color(float(v * w[0]), float(v * w[1]), float(v * w[2]));
}

std::string sampled_problem(const std::vector<double>& nm, const std::vector<double>& values) {
    if (nm.size() != values.size()) return "as many wavelengths as values are needed";
    if (nm.size() < 2)
        return fmt::format("a sampled spectrum needs at least two wavelength:value pairs, got {}",
                           nm.size());
    for (size_t i = 0; i < nm.size(); ++i) {
        if (!std::isfinite(nm[i]) || !std::isfinite(values[i]))
            return fmt::format("pair {} ({}:{}) is not finite", i + 1, nm[i], values[i]);
        if (nm[i] <= 0)
            return fmt::format("wavelength {} nm (pair {}) is not positive", nm[i], i + 1);
        if (i > 0 && nm[i] <= nm[i - 1])
            return fmt::format("wavelengths must increase: {} nm (pair {}) follows {} nm", nm[i],
                               i + 1, nm[i - 1]);
    }
    return {};
}

double planck(double nm, double kelvin) {
    // CODATA 2018 exact constants.
    constexpr double c = 299792458.0, h = 6.62607015e-34, k = 1.380649e-23;
    const double lambda = nm * 1e-9;
    const double per_m =
        2 * h * c * c / (std::pow(lambda, 5) * std::expm1(h * c / (lambda * k * kelvin)));
    return per_m * 1e-9;  // per metre of wavelength -> per nanometre
}

}  // namespace femto::spectrum
