// Internal: sampled spectra to femto's linear RGB, as Mitsuba 3's RGB variants convert the
// spectra of a scene file (docs/compatibility.md, "Spectra").
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "femto/color.h"

namespace femto::spectrum {

/// How a parameter uses its spectrum; it decides the conversion, as in Mitsuba 3.
enum class Use {
    Reflectance,  ///< bounded (albedos, reflectances): seen under D65, RGB clamped to [0, 1]
    Unbounded,    ///< eta, k, sigma_t, ...: seen under D65, negative RGB clamped to 0
    Emission,     ///< parameters of an emitter: unweighted, negative RGB clamped to 0
};

/// The range Mitsuba 3 integrates over, in nm.
inline constexpr double kMinNm = 360, kMaxNm = 830;

/// CIE 1931 2-degree colour matching functions (x-bar, y-bar, z-bar) at `nm`, linearly
/// interpolated in the 5 nm CIE table; zero outside [360, 830].
std::array<double, 3> cie1931_xyz(double nm);
/// CIE D65 illuminant, relative (1.0 at 560 nm), linearly interpolated; zero outside.
double cie_d65(double nm);
/// CIE XYZ to linear sRGB (Rec. 709 primaries, D65 white).
std::array<double, 3> xyz_to_linear_srgb(const std::array<double, 3>& xyz);

struct Conversion {
    std::array<double, 3> xyz{};  ///< before the matrix and the clamp
    Color rgb;
    bool clamped = false;  ///< the RGB left the valid range and was clamped
};

/// Converts the spectrum `value(nm)`, defined on [lo, hi] nm and zero elsewhere.
Conversion convert(const std::function<double(double)>& value, double lo, double hi, Use use);
/// A sampled spectrum, linearly interpolated between its samples and zero outside them.
/// The samples must pass sampled_problem().
Conversion convert_sampled(const std::vector<double>& nm, const std::vector<double>& values,
                           Use use);
/// A constant spectrum (Mitsuba's "uniform"): grey `v`, except for emission, which Mitsuba 3
/// converts as an equal-energy spectrum, v * M * (1, 1, 1) with M the XYZ-to-sRGB matrix.
Color convert_uniform(double v, Use use);

/// Why the samples cannot be a spectrum ("" when they can): fewer than two, wavelengths not
/// positive or not increasing, non-finite numbers.
std::string sampled_problem(const std::vector<double>& nm, const std::vector<double>& values);

/// Planck's law: spectral radiance of a black body at `kelvin`, in W m^-2 sr^-1 nm^-1.
double planck(double nm, double kelvin);

}  // namespace femto::spectrum
