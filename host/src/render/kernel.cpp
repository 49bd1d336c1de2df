// Density-estimation kernels (femto/kernel.h). The ball integrals are closed forms of
// integral_{|x| < 1} kernel_profile(|x|) dx; tests/unit/test_kernel.cpp checks them, and the
// CDFs, against quadrature.
#include "femto/kernel.h"

#include <fmt/format.h>

#include <cmath>

namespace femto {

namespace {

struct ShapeName {
    KernelShape shape;
    const char* name;
};
constexpr ShapeName kShapes[] = {{KernelShape::Box, "box"},
                                 {KernelShape::Epanechnikov, "epanechnikov"},
                                 {KernelShape::Perlin, "perlin"},
                                 {KernelShape::Gaussian, "gaussian"}};

constexpr double kPiD = 3.14159265358979323846;  // (femto::kPi is a float)

// The Gaussian's sigma is 1/3: profile exp(-u^2 / (2 sigma^2)) = exp(-4.5 u^2).
constexpr double kGaussA = 4.5;

}  // namespace

KernelShape read_kernel_shape(const Properties& props, const std::string& name,
                              const std::string& default_shape) {
    const std::string value = props.get_string(name, default_shape);
    for (const ShapeName& s : kShapes)
        if (value == s.name) return s.shape;
    props.fail(name, fmt::format("unknown kernel \"{}\"; valid: box, epanechnikov, perlin, "
                                 "gaussian",
                                 value));
}

const char* kernel_shape_name(KernelShape shape) {
    for (const ShapeName& s : kShapes)
        if (s.shape == shape) return s.name;
    return "?";
}

double kernel_profile(KernelShape shape, double u) {
    const double x = std::abs(u);
    if (!(x < 1.0)) return 0.0;
    switch (shape) {
        case KernelShape::Box:
            return 1.0;
        case KernelShape::Epanechnikov:
            return 1.0 - x * x;
        case KernelShape::Perlin:
            return 1.0 - x * x * x * (10.0 + x * (-15.0 + 6.0 * x));
        case KernelShape::Gaussian:
            return std::exp(-kGaussA * x * x);
    }
    return 0.0;
}

double kernel_cdf(KernelShape shape, double u) {
    if (u <= -1.0) return 0.0;
    if (u >= 1.0) return 1.0;
    switch (shape) {
        case KernelShape::Box:
            return 0.5 * (u + 1.0);
        case KernelShape::Epanechnikov:  // density 3/4 (1 - u^2)
            return 0.5 + 0.75 * u - 0.25 * u * u * u;
        case KernelShape::Perlin: {  // density = profile (its integral over [-1, 1] is 1)
            const double x = std::abs(u), x4 = x * x * x * x;
            const double half = x - 2.5 * x4 + 3.0 * x4 * x - x4 * x * x;  // integral over [0, x]
            return u >= 0 ? 0.5 + half : 0.5 - half;
        }
        case KernelShape::Gaussian: {  // truncated at 3 sigma and renormalised
            static const double norm = std::erf(3.0 / std::sqrt(2.0));
            return 0.5 + 0.5 * std::erf(3.0 * u / std::sqrt(2.0)) / norm;
        }
    }
    return 0.0;
}

double kernel_ball_integral(KernelShape shape, int dims) {
    if (dims < 1 || dims > 3) throw std::invalid_argument("kernel_ball_integral: dims 1, 2 or 3");
    const double a = kGaussA;
    switch (shape) {
        case KernelShape::Box:
            return dims == 1 ? 2.0 : dims == 2 ? kPiD : 4.0 * kPiD / 3.0;
        case KernelShape::Epanechnikov:
            return dims == 1 ? 4.0 / 3.0 : dims == 2 ? kPiD / 2.0 : 8.0 * kPiD / 15.0;
        case KernelShape::Perlin:
            return dims == 1 ? 1.0 : dims == 2 ? 2.0 * kPiD / 7.0 : 5.0 * kPiD / 21.0;
        case KernelShape::Gaussian:
            if (dims == 1) return std::sqrt(kPiD / a) * std::erf(std::sqrt(a));
            if (dims == 2) return kPiD * (1.0 - std::exp(-a)) / a;
            return 4.0 * kPiD *
                   (std::sqrt(kPiD) * std::erf(std::sqrt(a)) / (4.0 * a * std::sqrt(a)) -
                    std::exp(-a) / (2.0 * a));
    }
    return 0.0;
}

double progressive_shrink(double alpha, uint64_t iteration) {
    const double j = double(iteration) + 1.0;
    return std::exp(std::lgamma(alpha + j) - std::lgamma(alpha + 1.0) - std::lgamma(j + 1.0));
}

}  // namespace femto
