// femto testing kit: the integrator conformance matrix (installed with the SDK, target
// femto::testing; needs GoogleTest). Every integrator, built in or out of tree, runs the same
// analytic checks, each a TEST_P of the suite IntegratorConformance:
//   TimeIntegralIsTheSteadyImage   a transient cube summed over time equals the steady image
//                                  of the same integrator and seed (a scene with glass,
//                                  fluorescence and interreflections)
//   TofPlaneArrivalAndAmplitude    a point light over a Lambertian plane: each pixel's light
//                                  arrives when its footprint's geometry says (camera and
//                                  world time, and world time behind a null boundary), with
//                                  the closed-form amplitude rho / pi * I cos / d^2
//   FurnaceIsAGeometricSeries      inside an emitting diffuse sphere L = Le (1 + a + ... a^(D-1))
//   FluorescenceDelayAndColour     a fluorescent plane re-emits the blue it absorbs as green,
//                                  one lifetime later on average
//   GlassSlabDelay                 a glass slab of index eta and thickness d delays light by
//                                  (eta - 1) d and passes (1 - R)^2 of it at normal incidence
//   MaskPassesWithoutDelay         an emitter seen through a `mask` of opacity alpha: 1 - alpha
//                                  of its light, at the time it arrives without the mask
//   TimeOfFlightIsExactAtEveryScale  through glass, off a mirror, to a lit wall: the arrival
//                                  holds to 1e-6 relative and the amplitude stays the same at
//                                  scales 1e-6 ... 1e6 (not for density estimators)
//   SingleScatteringInAMedium      the exact single-scattering term along a camera ray in fog
//                                  (for a density estimator: smoothed by its kernels, photon
//                                  points' or beams')
// A check an integrator cannot take (a path depth it never reaches, media) is skipped with the
// reason. To join, an integrator adds one line to a test file that includes this header once:
//
//     #include <femto/testing/integrator_conformance.h>
//     using femto::testing::IntegratorCase;
//     using femto::testing::IntegratorConformance;
//     INSTANTIATE_TEST_SUITE_P(Mine, IntegratorConformance,
//                              ::testing::Values(IntegratorCase{"mine", "", -1, false}),
//                              femto::testing::case_name);
//
// Tolerances come from each estimate's standard error (4 SE, two-sided) or, where both sides
// use the same random numbers, from float rounding.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "femto/host.h"
#include "femto/sensor.h"
#include "femto/testing/media.h"
#include "femto/testing/render.h"

namespace femto::testing {

/// One integrator in the matrix.
struct IntegratorCase {
    std::string type;  ///< the plugin's type name (also the test's name)
    /// XML inside <integrator>; may use $max_depth, which each check sets to the path depth
    /// (in segments: 2 = direct light) it needs.
    std::string parameters;
    /// The path depth the integrator always computes when it has no max_depth (e.g. 2 for
    /// direct lighting); -1 when $max_depth sets it.
    int fixed_depth = -1;
    bool media = false;  ///< renders participating media
    /// It reaches the sensor only by connecting light paths to it (light tracing) and so needs
    /// a pinhole: the time-of-flight plane and fluorescence checks look through one instead of
    /// an orthographic camera, which no connection can reach; the checks that see their light
    /// only through glass or a mirror (which no connection passes), or through a one-pixel
    /// camera in fog, are skipped.
    bool connects_to_sensor = false;
    /// For a density estimator (photon mapping): the largest radius and time half-width of its
    /// kernels with the `parameters` given (0 for unbiased integrators). Light it estimates at a
    /// point may come from photons up to `kernel_radius` away and is spread over
    /// +-`kernel_time`, so the tof-plane check widens each pixel's bins by that reach and
    /// compares amplitudes over 16 seeds (every pixel of a pass shares its photons), and the
    /// check through a one-pixel footprint of 1e-4 at every scale is skipped (no photon lands
    /// there at any affordable count; the tof-plane and glass-slab checks hold the arrival).
    double kernel_radius = 0;
    double kernel_time = 0;
    /// For a density estimator in media: the radius of its 3D (volume) kernel. The media check
    /// compares it with the closed form smoothed by exactly its kernels, so the `parameters`
    /// must make them boxes of radius `volume_radius` and half-width `kernel_time` that do not
    /// shrink over the check's passes (a schedule with alpha within 1e-6 of 1); 0 skips it.
    double volume_radius = 0;
    /// The dimension of that volume kernel: 3 for photons (a ball around the camera point), 1
    /// for photon beams (a blur across each beam, at its closest approach to the camera ray).
    int volume_dims = 3;
    /// The time half-width of the volume kernel, when only media are density-estimated (photon
    /// beams); 0: `kernel_time`.
    double volume_time = 0;
    /// It renders only scenes with participating media (photon beams): the checks in scenes
    /// without a medium are skipped.
    bool media_only = false;
    bool density_estimate() const { return kernel_radius > 0 || kernel_time > 0; }
};

/// How GoogleTest prints a case.
inline void PrintTo(const IntegratorCase& c, std::ostream* os) { *os << c.type; }

/// Test-name generator for INSTANTIATE_TEST_SUITE_P.
inline std::string case_name(const ::testing::TestParamInfo<IntegratorCase>& info) {
    return info.param.type;
}

class IntegratorConformance : public ::testing::TestWithParam<IntegratorCase> {
protected:
    /// The path depth a check runs with: `wanted` when the integrator takes max_depth, else
    /// its fixed depth.
    int depth(int wanted) const {
        return GetParam().fixed_depth >= 0 ? GetParam().fixed_depth : wanted;
    }
    /// True when a check whose scene has no participating medium must be skipped (the
    /// integrator needs one): the check says `if (skips_media_free_scenes()) GTEST_SKIP()`.
    bool skips_media_free_scenes() const { return GetParam().media_only; }
    /// True when the integrator cannot see through an orthographic camera.
    bool needs_connectable_sensor() const { return GetParam().connects_to_sensor; }
    /// MaskPassesWithoutDelay through a pinhole (for integrators that connect to the sensor).
    void mask_through_pinhole(double alpha, double start, double width, int bins, int res,
                              int spp) const;
    std::string integrator() const {
        return "<integrator type=\"" + GetParam().type + "\">" + GetParam().parameters +
               "</integrator>";
    }
    /// Loads `body` (everything but the integrator) with $max_depth = depth.
    std::unique_ptr<Scene> load(const std::string& body, int depth) const {
        LoadOptions options;
        if (GetParam().parameters.find("$max_depth") != std::string::npos)
            options.defines = {{"max_depth", std::to_string(depth)}};
        return load_scene_string("<scene version=\"3.0.0\">" + integrator() + body + "</scene>",
                                 options);
    }
};

namespace conformance {

inline std::string num(double v) {
    std::ostringstream s;
    s.precision(17);
    s << v;
    return s.str();
}

/// A transient film (box pixel filter, histogram in time).
inline std::string transient_film(int res, double start, double width, int bins,
                                  bool world_time = false, const std::string& extra = "") {
    return "<film type=\"transient\"><integer name=\"width\" value=\"" + std::to_string(res) +
           "\"/><integer name=\"height\" value=\"" + std::to_string(res) +
           "\"/><float name=\"start\" value=\"" + num(start) +
           "\"/><float name=\"bin_width\" value=\"" + num(width) +
           "\"/><integer name=\"bins\" value=\"" + std::to_string(bins) +
           "\"/><boolean name=\"world_time\" value=\"" + (world_time ? "true" : "false") + "\"/>" +
           extra + "<rfilter type=\"box\"/></film>";
}

inline std::string steady_film(int res) {
    return "<film type=\"hdrfilm\"><integer name=\"width\" value=\"" + std::to_string(res) +
           "\"/><integer name=\"height\" value=\"" + std::to_string(res) +
           "\"/><rfilter type=\"box\"/></film>";
}

inline std::string sampler(int spp) {
    return "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"" +
           std::to_string(spp) + "\"/></sampler>";
}

/// An orthographic camera at height `height` above the plane z = 0, looking down, seeing
/// [-half, half]^2 (`extra`: more sensor parameters).
inline std::string camera_above(double height, double half, int spp, const std::string& film,
                                const std::string& extra = "") {
    return "<sensor type=\"orthographic\"><transform name=\"to_world\"><scale x=\"" + num(half) +
           "\" y=\"" + num(half) + "\"/><lookat origin=\"0,0," + num(height) +
           "\" target=\"0,0,0\" up=\"0,1,0\"/></transform>" + extra + sampler(spp) + film +
           "</sensor>";
}

/// A pinhole camera at height `height` above the origin, looking down, whose image covers
/// [-half, half]^2 of the plane z = 0 as camera_above()'s does: for integrators that reach the
/// sensor only by connections.
inline std::string pinhole_above(double height, double half, int spp, const std::string& film) {
    const double fov = 2 * std::atan(half / height) * 180 / M_PI;
    return "<sensor type=\"perspective\"><float name=\"fov\" value=\"" + num(fov) +
           "\"/><transform name=\"to_world\"><lookat origin=\"0,0," + num(height) +
           "\" target=\"0,0,0\" up=\"0,1,0\"/></transform>" + sampler(spp) + film + "</sensor>";
}

inline std::string point_light(const std::string& position, double intensity) {
    return "<emitter type=\"point\"><point name=\"position\" value=\"" + position +
           "\"/><float name=\"intensity\" value=\"" + num(intensity) + "\"/></emitter>";
}

}  // namespace conformance

// ---- the time integral of a transient render is the steady render ---------------------------

TEST_P(IntegratorConformance, TimeIntegralIsTheSteadyImage) {
    using namespace conformance;
    if (skips_media_free_scenes())
        GTEST_SKIP() << "renders only scenes with participating media; this one has none";
    // An open box (floor, back and red left wall), a glass sphere, a fluorescent sphere and an
    // area light. With the same seed a transient and a steady film see the same random numbers,
    // so their images agree to float rounding (the cube sums per bin in float, hdrfilm in
    // double: 1e-4 relative), provided the window holds every path: the camera segment is at
    // most 9, each further one at most 1.6 * 4.9 (glass), and up to D fluorescence delays of
    // mean 0.2 stay below 50 with probability 1 - 1e-40 (the window is [0, 100)).
    const int D = depth(5), res = 12, spp = 8;
    const std::string walls =
        "<shape type=\"rectangle\"><transform name=\"to_world\"><rotate x=\"1\" angle=\"-90\"/>"
        "<translate y=\"-1\"/></transform><bsdf type=\"diffuse\"/></shape>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><translate z=\"-1\"/></transform>"
        "<bsdf type=\"diffuse\"/></shape>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><rotate y=\"1\" angle=\"90\"/>"
        "<translate x=\"-1\"/></transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" "
        "value=\"0.6,0.1,0.1\"/></bsdf></shape>"
        "<shape type=\"sphere\"><point name=\"center\" value=\"0.4,-0.6,0\"/><float "
        "name=\"radius\" value=\"0.4\"/><bsdf type=\"dielectric\"><float name=\"int_ior\" "
        "value=\"1.6\"/></bsdf></shape>"
        "<shape type=\"sphere\"><point name=\"center\" value=\"-0.4,-0.7,-0.4\"/><float "
        "name=\"radius\" value=\"0.3\"/><bsdf type=\"fluorescent\"><rgb name=\"absorption\" "
        "value=\"0,0,0.8\"/><rgb name=\"emission\" value=\"1,0.2,0\"/><rgb "
        "name=\"reflectance\" value=\"0.2,0.5,0.1\"/><float name=\"lifetime\" value=\"0.2\"/>"
        "</bsdf></shape>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.3\"/><rotate "
        "x=\"1\" angle=\"90\"/><translate y=\"0.99\"/></transform><emitter type=\"area\"><rgb "
        "name=\"radiance\" value=\"8,7,6\"/></emitter></shape>";
    // Media-capable integrators also render the box filled with fog that holds the camera
    // (sigma_t 0.35: a segment longer than 100 has probability e^-35).
    for (const bool fog : {false, true}) {
        if (fog && !GetParam().media) continue;
        SCOPED_TRACE(fog ? "in fog" : "in vacuum");
        const std::string medium =
            fog ? "<medium type=\"homogeneous\" id=\"fog\"><float name=\"sigma_s\" "
                  "value=\"0.3\"/><float name=\"sigma_a\" value=\"0.05\"/></medium>"
                : "";
        auto camera = [&](const std::string& film) {
            return medium +
                   "<sensor type=\"perspective\"><float name=\"fov\" value=\"50\"/><transform "
                   "name=\"to_world\"><lookat origin=\"0,0,3.5\" target=\"0,0,0\" "
                   "up=\"0,1,0\"/></transform>" +
                   (fog ? "<ref id=\"fog\"/>" : "") + sampler(spp) + film + "</sensor>";
        };
        auto transient = load(camera(transient_film(res, 0, 0.25, 400)) + walls, D);
        auto steady = load(camera(steady_film(res)) + walls, D);
        expect_same_image(render_steady(*transient, 23), render_steady(*steady, 23),
                          "cube summed over time", "steady");
    }
}

// ---- time of flight over a plane ------------------------------------------------------------

namespace conformance {

// A point light of intensity kTofI at height kTofH over a Lambertian plane of albedo kTofRho,
// seen from height kTofCamera by an orthographic camera covering [-2, 2]^2.
constexpr double kTofH = 1.5, kTofI = 5, kTofRho = 0.6, kTofCamera = 5, kTofHalf = 2;

inline std::string tof_plane(int spp, const std::string& film, const std::string& bsdf,
                             bool pinhole = false) {
    return (pinhole ? pinhole_above(kTofCamera, kTofHalf, spp, film)
                    : camera_above(kTofCamera, kTofHalf, spp, film)) +
           "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"10\"/>"
           "</transform>" +
           bsdf + "</shape>" + point_light("0,0," + num(kTofH), kTofI);
}

// Pixel (px, py)'s footprint [x0, x1] x [y0, y1] on the plane (row 0 at the top, +y).
struct Footprint {
    double x0, x1, y0, y1;
    double r_min() const { return std::hypot(std::max({0.0, x0, -x1}), std::max({0.0, y0, -y1})); }
    double r_max() const {
        return std::hypot(std::max(std::abs(x0), std::abs(x1)),
                          std::max(std::abs(y0), std::abs(y1)));
    }
};
inline Footprint footprint(int res, int px, int py) {
    const double w = 2 * kTofHalf / res;
    // The orthographic camera looks down -z with up = +y: image x runs along -x in world. (The
    // pinhole's image may be mirrored; the scene is symmetric in x and y, so every value
    // checked is the same for the mirrored footprint.)
    const double xa = kTofHalf - px * w, ya = kTofHalf - py * w;
    return {xa - w, xa, ya - w, ya};
}

// The bins pixel (px, py)'s light may arrive in: light reaches a plane point at distance r from
// the axis after sqrt(r^2 + H^2), and the camera sqrt(r^2 + kTofCamera^2) later through the
// pinhole, kTofCamera later through the orthographic camera, or at once in world time. Both
// grow with r, so the footprint's nearest and farthest points bound them (1e-6: float rounding
// of lengths of ~7 to 6e-8 relative).
inline std::pair<int, int> tof_bins(const Footprint& f, double start, double width, int bins,
                                    bool world_time, bool pinhole, double kernel_radius = 0,
                                    double kernel_time = 0) {
    // A density estimate at r also counts photons that arrived at r +- kernel_radius (the light
    // path's part of the time), spread by +-kernel_time.
    auto arrival = [&](double r, double light_r) {
        const double sensor = world_time ? 0.0 : pinhole ? std::hypot(r, kTofCamera) : kTofCamera;
        return sensor + std::hypot(light_r, kTofH);
    };
    const double r0 = f.r_min(), r1 = f.r_max();
    return {bin_of(start, width, bins,
                   arrival(r0, std::max(0.0, r0 - kernel_radius)) - kernel_time - 1e-6),
            bin_of(start, width, bins, arrival(r1, r1 + kernel_radius) + kernel_time + 1e-6)};
}

// The footprint's mean of the closed-form radiance rho / pi * I * H / d^3 (each camera sample
// sees one point of it: the plane is parallel to the image, so pixel samples are uniform on the
// footprint), and its standard deviation there, on a 32 x 32 grid.
inline MeanAndError footprint_radiance(const Footprint& f) {
    const int grid = 32;
    double s = 0, s2 = 0;
    for (int j = 0; j < grid; ++j)
        for (int i = 0; i < grid; ++i) {
            const double x = f.x1 - (i + 0.5) / grid * (f.x1 - f.x0);
            const double y = f.y1 - (j + 0.5) / grid * (f.y1 - f.y0);
            const double d2 = x * x + y * y + kTofH * kTofH;
            const double v = kTofRho / M_PI * kTofI * kTofH / (d2 * std::sqrt(d2));
            s += v, s2 += v * v;
        }
    const double mean = s / (grid * grid);
    return {mean, std::sqrt(std::max(0.0, s2 / (grid * grid) - mean * mean))};
}

// Energy outside pixel (px, py)'s allowed bins of `cube` (reported as a failure) and inside.
inline double tof_pixel_energy(const Cube& cube, int px, int py, std::pair<int, int> allowed,
                               int& failures) {
    double inside = 0, outside = 0;
    for (int t = 0; t < cube.T; ++t)
        (t < allowed.first || t > allowed.second ? outside : inside) += cube.energy(py, px, t) / 3;
    if (outside != 0 && ++failures <= 10)
        ADD_FAILURE() << "pixel " << px << "," << py << ": " << outside << " outside bins ["
                      << allowed.first << ", " << allowed.second << "]";
    return inside;
}

}  // namespace conformance

TEST_P(IntegratorConformance, TofPlaneArrivalAndAmplitude) {
    using namespace conformance;
    if (skips_media_free_scenes())
        GTEST_SKIP() << "renders only scenes with participating media; this one has none";
    // Every pixel's energy must lie in the bins its footprint spans (tof_bins(): camera and
    // world time); its time integral is the footprint's mean of rho / pi * I * H / d^3. The
    // third run, world time behind an index-matched boundary (a clear medium between null
    // surfaces at z = 2.5 and 3.5), checks that the sensor distance is the first scattering
    // vertex's, not the first surface's. Through the orthographic camera a camera sample's only
    // randomness is its position in the pixel, so each pixel is within 4 SE of the jittered
    // positions; an integrator that needs a pinhole (light tracing) is checked over 16 seeds,
    // by a chi-square of the pixels' deviations in units of their spread across the seeds.
    const bool pinhole = needs_connectable_sensor();
    const bool by_seeds = pinhole || GetParam().density_estimate();
    for (const int run : {0, 1, 2}) {
        const bool world = run > 0;
        if (run == 2 && !GetParam().media) continue;
        SCOPED_TRACE(run == 0 ? "camera time" : run == 1 ? "world time" : "world, null boundary");
        // (Through the pinhole the corners' camera segment is longer: up to 9.0 in camera time.)
        const int res = 16, spp = 64, bins = pinhole && !world ? 520 : 370,
                  seeds = by_seeds ? 16 : 1;
        const double start = world ? 1.4 : 6.4, width = 0.005;
        const std::string boundary =
            run < 2 ? ""
                    : "<medium type=\"homogeneous\" id=\"clear\"><float name=\"sigma_t\" "
                      "value=\"0\"/><float name=\"albedo\" value=\"0\"/></medium><shape "
                      "type=\"cube\"><transform name=\"to_world\"><scale x=\"4\" y=\"4\" "
                      "z=\"0.5\"/><translate z=\"3\"/></transform><bsdf type=\"null\"/><ref "
                      "name=\"interior\" id=\"clear\"/></shape>";
        // A scene per seed: a film accumulates every render of its scene.
        std::vector<Cube> cubes;
        for (int seed = 0; seed < seeds; ++seed) {
            auto scene = load(
                boundary + tof_plane(spp, transient_film(res, start, width, bins, world),
                                     "<bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"" +
                                         num(kTofRho) + "\"/></bsdf>",
                                     pinhole),
                depth(2));
            cubes.push_back(render_cube(*scene, uint64_t(17 + seed), "tof" + std::to_string(run)));
        }
        ASSERT_EQ(cubes[0].T, bins);
        int failures = 0;
        double chi2 = 0, total = 0, total_expected = 0, total_var = 0;
        for (int py = 0; py < res; ++py)
            for (int px = 0; px < res; ++px) {
                const Footprint f = footprint(res, px, py);
                const auto allowed = tof_bins(f, start, width, bins, world, pinhole,
                                              GetParam().kernel_radius, GetParam().kernel_time);
                ASSERT_GE(allowed.first, 0);
                std::vector<double> inside;
                for (const Cube& cube : cubes)
                    inside.push_back(tof_pixel_energy(cube, px, py, allowed, failures));
                const MeanAndError expected = footprint_radiance(f);
                if (by_seeds) {  // z^2 of the seeds' mean against their standard error
                    const MeanAndError m = mean_and_error(inside);
                    const double z = (m.mean - expected.mean) / m.standard_error;
                    chi2 += z * z;
                    total += m.mean, total_expected += expected.mean;
                    total_var += m.standard_error * m.standard_error;
                } else if (std::abs(inside[0] - expected.mean) >
                               4 * expected.standard_error / std::sqrt(double(spp)) +
                                   1e-5 * expected.mean &&
                           ++failures <= 10) {
                    ADD_FAILURE() << "pixel " << px << "," << py << ": " << inside[0]
                                  << ", expected " << expected.mean;
                }
            }
        EXPECT_EQ(failures, 0);
        if (by_seeds) {
            // z follows a t distribution with nu = seeds - 1: the bound is the mean of the sum
            // of the pixels' z^2 plus 3.72 of its standard deviations (as tests/unit's
            // agreement checks).
            const double nu = seeds - 1, n = double(res) * res;
            const double m = nu / (nu - 2),
                         v = 2 * nu * nu * (nu - 1) / ((nu - 2) * (nu - 2) * (nu - 4));
            EXPECT_LT(chi2, n * m + 3.72 * std::sqrt(n * v))
                << "pixel amplitudes: chi-square over " << n << " pixels (mean " << n * m << ")";
            // and the image's total (a bias common to all pixels): within 4 SE.
            EXPECT_NEAR(total, total_expected, 4 * std::sqrt(total_var));
        }
    }
}

// ---- furnace --------------------------------------------------------------------------------

TEST_P(IntegratorConformance, FurnaceIsAGeometricSeries) {
    using namespace conformance;
    if (skips_media_free_scenes())
        GTEST_SKIP() << "renders only scenes with participating media; this one has none";
    // Inside a closed diffuse sphere of albedo a that emits Le everywhere, paths of at most D
    // segments gather L = Le (1 + a + ... + a^(D-1)).
    const int D = depth(6);
    if (D < 0) GTEST_SKIP() << "needs a finite path depth";
    const double albedo = 0.6, Le = 1.0;
    double expected = 0, term = Le;
    for (int k = 0; k < D; ++k, term *= albedo) expected += term;
    auto scene = load(
        "<sensor type=\"perspective\"><float name=\"fov\" value=\"60\"/>" + sampler(16) +
            steady_film(24) +
            "</sensor><shape type=\"sphere\"><float name=\"radius\" value=\"3\"/><boolean "
            "name=\"flip_normals\" value=\"true\"/><bsdf type=\"diffuse\"><float "
            "name=\"reflectance\" value=\"" +
            num(albedo) + "\"/></bsdf><emitter type=\"area\"><float name=\"radiance\" value=\"" +
            num(Le) + "\"/></emitter></shape>",
        D);
    const MeanAndError m = pixel_mean(render_steady(*scene, 7), 1);
    // 4 SE, plus a known systematic floor: today's fixed ray-origin offset (1e-4 max(1, |p|))
    // moves the hit points of grazing BSDF samples, so their MIS weights and the light
    // samples' no longer sum to exactly 1 (measured -0.7e-4 relative for direct lighting,
    // -1.3e-4 at depth 6; BSDF sampling alone is exact). Offsets that follow the floating-point
    // error of the hit point remove it.
    EXPECT_NEAR(m.mean, expected, 4 * m.standard_error + 2e-4 * expected)
        << "depth " << D << ", standard error " << m.standard_error;
}

// ---- fluorescence ---------------------------------------------------------------------------

TEST_P(IntegratorConformance, FluorescenceDelayAndColour) {
    using namespace conformance;
    if (skips_media_free_scenes())
        GTEST_SKIP() << "renders only scenes with participating media; this one has none";
    const bool pinhole = needs_connectable_sensor();
    // The tof plane, fluorescent: it absorbs the blue third of the white light and re-emits it
    // as green after an exponential delay of mean tau (efficiency 1, no elastic reflection).
    // Against the same plane white and Lambertian: green carries what blue carried there, red
    // and blue are black, and light arrives tau later on average (the window holds 30 tau).
    const int res = 16, spp = 32, bins = 800;
    const double start = 6.4, width = 0.02, tau = 0.5;
    const std::string film = transient_film(res, start, width, bins);
    auto white = load(tof_plane(spp, film,
                                "<bsdf type=\"diffuse\"><float name=\"reflectance\" "
                                "value=\"1\"/></bsdf>",
                                pinhole),
                      depth(2));
    auto fluorescent =
        load(tof_plane(spp, film,
                       "<bsdf type=\"fluorescent\"><rgb name=\"absorption\" value=\"0,0,1\"/><rgb "
                       "name=\"emission\" value=\"0,1,0\"/><float name=\"efficiency\" "
                       "value=\"1\"/><float name=\"lifetime\" value=\"" +
                           num(tau) + "\"/></bsdf>",
                       pinhole),
             depth(2));
    const Cube ref = render_cube(*white, 31, "fluo-white");
    const Cube fl = render_cube(*fluorescent, 31, "fluo");
    // Per pixel, the green the fluorescent plane sends minus the blue the white one sends: a
    // paired difference whose mean over pixels must vanish within 4 of its standard errors
    // (1e-4 relative for float rounding when both renders draw the same numbers).
    double red = 0, blue = 0, ref_total = 0;
    std::vector<double> difference;  // per pixel
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) {
            double green = 0, ref_blue = 0;
            for (int t = 0; t < bins; ++t) {
                red += std::abs(fl.at(y, x, t, 0)), blue += std::abs(fl.at(y, x, t, 2));
                green += fl.at(y, x, t, 1), ref_blue += ref.at(y, x, t, 2);
            }
            difference.push_back(green - ref_blue);
            ref_total += ref_blue;
        }
    EXPECT_EQ(red, 0.0);
    EXPECT_EQ(blue, 0.0);
    const double n = double(res) * res;
    const MeanAndError d = mean_and_error(difference);
    EXPECT_GT(ref_total, 0.0);
    EXPECT_NEAR(d.mean, 0.0, 4 * d.standard_error + 1e-4 * ref_total / n)
        << "green re-emitted " << d.mean + ref_total / n << " per pixel, blue absorbed "
        << ref_total / n;
    const MeanAndError a = mean_arrival(ref, start, width), b = mean_arrival(fl, start, width);
    // Binning: each arrival's bin centre is within width / 2 of it.
    EXPECT_NEAR(b.mean - a.mean, tau, 4 * std::hypot(a.standard_error, b.standard_error) + width)
        << "mean arrival " << b.mean << " against " << a.mean << " without fluorescence";
}

// ---- refraction delay -----------------------------------------------------------------------

TEST_P(IntegratorConformance, GlassSlabDelay) {
    using namespace conformance;
    if (skips_media_free_scenes())
        GTEST_SKIP() << "renders only scenes with participating media; this one has none";
    if (needs_connectable_sensor())
        GTEST_SKIP() << "the emitter is seen only through glass, and no connection to the sensor "
                        "passes a specular surface (test_light_tracer.cpp checks the light "
                        "tracer's glass delay from the side)";
    // An emitting rectangle (radiance 1, black) at z = 0 seen from above through a glass slab
    // of index eta filling 1 <= z <= 1 + d. Straight through, light arrives at camera time
    // 5 + (eta - 1) d; 2k internal reflections add 2 k eta d. At normal incidence a camera
    // sample crosses both faces with probability (1 - R)^2, R = ((eta - 1) / (eta + 1))^2.
    const int D = depth(7);
    if (D >= 0 && D < 3) GTEST_SKIP() << "light through a slab needs paths of 3 segments";
    const double d = 0.5, eta = 1.5, start = 4.905, width = 0.02;
    const int bins = 200, res = 8, spp = 64;
    auto scene = load(
        camera_above(5, 1, spp, transient_film(res, start, width, bins)) +
            "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/>"
            "</transform><bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"0\"/></bsdf>"
            "<emitter type=\"area\"><float name=\"radiance\" value=\"1\"/></emitter></shape>"
            "<shape type=\"cube\"><transform name=\"to_world\"><scale x=\"3\" y=\"3\" z=\"" +
            num(d / 2) + "\"/><translate z=\"" + num(1 + d / 2) +
            "\"/></transform><bsdf type=\"dielectric\"><float name=\"int_ior\" value=\"" +
            num(eta) + "\"/><float name=\"ext_ior\" value=\"1\"/></bsdf></shape>",
        D);
    const Cube cube = render_cube(*scene, 5, "slab");
    ASSERT_EQ(cube.T, bins);
    std::vector<bool> allowed(size_t(bins), false);
    const int first = bin_of(start, width, bins, 5 + (eta - 1) * d);
    ASSERT_GE(first, 0);
    for (int k = 0;; ++k) {
        const int b = bin_of(start, width, bins, 5 + (eta - 1) * d + 2 * k * eta * d);
        if (b < 0) break;
        allowed[size_t(b)] = true;
    }
    double through = 0;
    int misplaced = 0;
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) {
            for (int t = 0; t < bins; ++t)
                if (!allowed[size_t(t)] && cube.energy(y, x, t) != 0 && ++misplaced <= 5)
                    ADD_FAILURE() << "pixel " << x << "," << y << ": light in bin " << t
                                  << "; straight through it arrives in bin " << first;
            through += cube.at(y, x, first, 0);
        }
    EXPECT_EQ(misplaced, 0);
    const double R = std::pow((eta - 1) / (eta + 1), 2), p = (1 - R) * (1 - R);
    const double n = double(res) * res * spp;
    EXPECT_NEAR(through / (res * res), p, 4 * std::sqrt(p * (1 - p) / n) + 1e-6);
}

// ---- opacity masks --------------------------------------------------------------------------

namespace conformance {
/// The scene of MaskPassesWithoutDelay but its camera: a mask of opacity `alpha` over an emitter.
inline std::string mask_scene(double alpha) {
    return "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/>"
           "</transform><bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"0\"/></bsdf>"
           "<emitter type=\"area\"><float name=\"radiance\" value=\"1\"/></emitter></shape>"
           "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/>"
           "<translate z=\"2.5\"/></transform><bsdf type=\"mask\"><float name=\"opacity\" "
           "value=\"" +
           num(alpha) +
           "\"/><bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"0.5\"/></bsdf>"
           "</bsdf></shape>";
}
}  // namespace conformance

/// MaskPassesWithoutDelay for an integrator that reaches the sensor by connections (a light
/// tracer): through a pinhole at height 5 whose image covers [-1, 1]^2 of the emitter, pixel
/// (px, py) sees the emitter points of its footprint at distances sqrt(r^2 + 25), r between the
/// footprint's nearest and farthest points from the axis: every pixel's light lies in those
/// bins, and its time integral is 1 - alpha (the emitter's radiance through the mask). Pixel
/// estimates are independent with that expectation: their mean is compared within 4 standard
/// errors of their spread.
inline void IntegratorConformance::mask_through_pinhole(double alpha, double start, double width,
                                                        int bins, int res, int spp) const {
    using namespace conformance;
    auto scene =
        load(pinhole_above(5, 1, spp, transient_film(res, start, width, bins)) + mask_scene(alpha),
             depth(3));
    const Cube cube = render_cube(*scene, 11, "mask-pinhole");
    ASSERT_EQ(cube.T, bins);
    int failures = 0;
    std::vector<double> seen;
    const double w = 2.0 / res;
    for (int py = 0; py < res; ++py)
        for (int px = 0; px < res; ++px) {
            const double xa = 1 - px * w, ya = 1 - py * w;
            const Footprint f{xa - w, xa, ya - w, ya};
            const std::pair<int, int> allowed{
                bin_of(start, width, bins, std::hypot(f.r_min(), 5.0) - 1e-6),
                bin_of(start, width, bins, std::hypot(f.r_max(), 5.0) + 1e-6)};
            seen.push_back(tof_pixel_energy(cube, px, py, allowed, failures));
        }
    EXPECT_EQ(failures, 0);
    const MeanAndError m = mean_and_error(seen);
    EXPECT_NEAR(m.mean, 1 - alpha, 4 * m.standard_error)
        << "the emitter seen through a mask of opacity " << alpha;
}

TEST_P(IntegratorConformance, MaskPassesWithoutDelay) {
    using namespace conformance;
    if (skips_media_free_scenes())
        GTEST_SKIP() << "renders only scenes with participating media; this one has none";
    // An emitting rectangle (radiance 1, black) at z = 0 seen from above at height 5 by an
    // orthographic camera (a pinhole for light tracers: mask_through_pinhole()) through a
    // mask of opacity alpha at z = 2.5 over a diffuse material facing the camera (unlit: the
    // emitter shines on its back). Every camera sample passes the mask straight (weight 1) with
    // probability 1 - alpha and arrives at camera time 5, as without the mask: the arrival bin
    // holds a binomial proportion of mean 1 - alpha, every other bin nothing. The pass-through
    // counts as a bounce toward max_depth (Mitsuba 3's `path`): paths of 2 segments.
    const int D = depth(3);
    if (D >= 0 && D < 2) GTEST_SKIP() << "light through a mask needs paths of 2 segments";
    const double alpha = 0.3, start = 4.905, width = 0.02;
    const int bins = 20, res = 8, spp = 64;
    if (needs_connectable_sensor()) {  // through a pinhole instead
        mask_through_pinhole(alpha, start, width, bins, res, spp);
        return;
    }
    const std::string film = transient_film(res, start, width, bins);
    auto scene = load(camera_above(5, 1, spp, film) + mask_scene(alpha), D);
    const Cube cube = render_cube(*scene, 11, "mask");
    ASSERT_EQ(cube.T, bins);
    const int arrival = bin_of(start, width, bins, 5.0);
    double through = 0;
    int misplaced = 0;
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) {
            for (int t = 0; t < bins; ++t)
                if (t != arrival && cube.energy(y, x, t) != 0 && ++misplaced <= 5)
                    ADD_FAILURE() << "pixel " << x << "," << y << ": light in bin " << t
                                  << "; without the mask it arrives in bin " << arrival;
            through += cube.at(y, x, arrival, 0);
        }
    EXPECT_EQ(misplaced, 0);
    const double p = 1 - alpha, n = double(res) * res * spp;
    EXPECT_NEAR(through / (res * res), p, 4 * std::sqrt(p * (1 - p) / n) + 1e-6);
}

// ---- exact time at every scale --------------------------------------------------------------

TEST_P(IntegratorConformance, TimeOfFlightIsExactAtEveryScale) {
    using namespace conformance;
    if (skips_media_free_scenes())
        GTEST_SKIP() << "renders only scenes with participating media; this one has none";
    if (needs_connectable_sensor())
        GTEST_SKIP() << "the wall is seen only through glass and a mirror, and no connection to "
                        "the sensor passes a specular surface";
    if (GetParam().density_estimate())
        GTEST_SKIP() << "a density estimate cannot resolve a footprint of 1e-4 (no photon lands in "
                        "it at any affordable count)";
    // The same scene at scales s = 1e-6 ... 1e6: an orthographic camera at height 5 s with a
    // tiny footprint looks down through a glass slab (index eta, 2 s <= z <= 2.5 s) at a mirror
    // tilted 45 degrees (the plane z = -x), which shows a diffuse wall at x = 5 s lit by a
    // point light at (s, 0, 0). Straight through, light arrives at camera time
    // s (5 + (eta - 1) d + 5 + 4) exactly (camera to mirror plus mirror to wall is 10 s for any
    // point of the footprint; the wall's light is 4 s away to 1e-8). Every bounce spawns a ray
    // from a surface and the wall connects to the light, so any ray-origin offset counted as
    // time (or not counted) shows as a shift. The arrival must hold to 1e-6 relative (float
    // geometry rounds to 6e-8 relative), and the amplitude (1 - R)^2 rho / pi * I / (4 s)^2,
    // with I = s^2, must be the same at every scale (4 SE).
    const int D = depth(5);
    if (D >= 0 && D < 5) GTEST_SKIP() << "the slab, mirror and wall need paths of 5 segments";
    const double eta = 1.5, d = 0.5, rho = 0.5;
    const double exact = 5 + (eta - 1) * d + 5 + 4;  // at scale 1
    const int spp = 256, bins = 40;
    for (int k = -6; k <= 6; ++k) {
        const double s = std::pow(10.0, k);
        SCOPED_TRACE("scale 1e" + std::to_string(k));
        // Bins of 1e-7 relative width: the arrival must land within +-10 bins of the exact one.
        const double width = 1e-7 * exact * s, start = exact * s - 0.5 * bins * width;
        const std::string scale = "<scale value=\"" + num(s) + "\"/>";
        auto scene = load(
            camera_above(5 * s, 1e-4 * s, spp, transient_film(1, start, width, bins),
                         "<float name=\"near_clip\" value=\"" + num(1e-3 * s) +
                             "\"/><float name=\"far_clip\" value=\"" + num(1e3 * s) + "\"/>") +
                "<shape type=\"cube\"><transform name=\"to_world\"><scale x=\"3\" y=\"3\" "
                "z=\"" +
                num(d / 2) + "\"/><translate z=\"" + num(2 + d / 2) + "\"/>" + scale +
                "</transform><bsdf type=\"dielectric\"><float name=\"int_ior\" value=\"" +
                num(eta) +
                "\"/><float name=\"ext_ior\" value=\"1\"/></bsdf></shape>"
                "<shape type=\"rectangle\"><transform name=\"to_world\"><rotate y=\"1\" "
                "angle=\"45\"/>" +
                scale +
                "</transform><bsdf type=\"conductor\"/></shape>"
                "<shape type=\"rectangle\"><transform name=\"to_world\"><rotate y=\"1\" "
                "angle=\"-90\"/><translate x=\"5\"/>" +
                scale + "</transform><bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"" +
                num(rho) + "\"/></bsdf></shape>" + point_light(num(s) + ",0,0", s * s),
            D);
        const Cube cube = render_cube(*scene, 11, "scale");
        ASSERT_EQ(cube.T, bins);
        const int lo = bins / 2 - 10, hi = bins / 2 + 10;
        double inside = 0, outside = 0;
        int first_outside = -1;
        for (int t = 0; t < bins; ++t) {
            const double e = cube.energy(0, 0, t) / 3;
            (t < lo || t >= hi ? outside : inside) += e;
            if ((t < lo || t >= hi) && e != 0 && first_outside < 0) first_outside = t;
        }
        EXPECT_EQ(outside, 0) << "light in bin " << first_outside << ", "
                              << (first_outside - bins / 2)
                              << " bins of 1e-7 relative from the exact arrival";
        const double R = std::pow((eta - 1) / (eta + 1), 2), p = (1 - R) * (1 - R);
        const double L = rho / kPi / 16;  // what a sample that passes the slab carries
        EXPECT_NEAR(inside, p * L, 4 * L * std::sqrt(p * (1 - p) / spp) + 1e-6 * L);
    }
}

// ---- single scattering ----------------------------------------------------------------------

TEST_P(IntegratorConformance, SingleScatteringInAMedium) {
    using namespace conformance;
    if (needs_connectable_sensor())
        GTEST_SKIP() << "a one-pixel camera ray needs an orthographic camera; through a pinhole "
                        "the pixel's cone is a vanishing target for light paths "
                        "(test_light_tracer.cpp compares the light tracer in fog with the path "
                        "tracer)";
    // A 1-pixel orthographic camera at the origin looks along +x through fog (sigma_a 0.1,
    // sigma_s 0.5, isotropic) lit by a point light of intensity 3 at (2, 1, 0). Paths of two
    // segments carry single scattering only: each bin against single_scattering()
    // (femto/testing/media.h) within 4 SE (the film's variance AOV) + 1e-4 relative.
    // A density estimator (volume_radius > 0) sees the closed form smoothed by its box
    // kernels, over 2000 passes.
    if (!GetParam().media) GTEST_SKIP() << "does not render participating media";
    const int D = depth(2);
    if (D != 2) GTEST_SKIP() << "needs paths of exactly 2 segments (single scattering)";
    const bool density = GetParam().density_estimate() || GetParam().volume_radius > 0;
    if (density && !(GetParam().volume_radius > 0))
        GTEST_SKIP() << "a density estimator states its volume kernel (volume_radius)";
    const Fog fog;
    const double start = 2.2, width = 0.05, intensity = 3;
    const int bins = 80;
    auto scene =
        load(fog.xml() +
                 "<sensor type=\"orthographic\"><float name=\"near_clip\" value=\"0\"/><transform "
                 "name=\"to_world\"><scale x=\"0.001\" y=\"0.001\"/><lookat origin=\"0,0,0\" "
                 "target=\"1,0,0\" up=\"0,0,1\"/></transform><ref id=\"fog\"/>" +
                 sampler(density ? 2000 : 20000) +
                 transient_film(1, start, width, bins, false,
                                "<string name=\"aovs\" value=\"variance\"/>") +
                 "</sensor>" + point_light("2,1,0", intensity),
             D);
    const auto [cube, variance] = render_cube_and_variance(*scene, 5, "single");
    ASSERT_EQ(cube.T, bins);
    // s + r(s) >= s, so no s past the window's end (plus a time kernel's reach) can arrive
    // inside it.
    const double end = start + bins * width;
    if (density) {
        const double T =
            GetParam().volume_time > 0 ? GetParam().volume_time : GetParam().kernel_time;
        const double s1 = (end + T) / fog.eta, R = GetParam().volume_radius;
        const auto expected =
            GetParam().volume_dims == 1
                ? single_scattering_beams(fog, {0, 0, 0}, {1, 0, 0}, {2, 1, 0}, intensity, 0.0, s1,
                                          start, width, bins, R, T)
                : single_scattering_smoothed(fog, {0, 0, 0}, {1, 0, 0}, {2, 1, 0}, intensity, 0.0,
                                             s1, start, width, bins, R, T);
        EXPECT_GT(expect_bins(cube, variance, expected, 1e-3), 60);
        return;
    }
    const auto expected = single_scattering(fog, {0, 0, 0}, {1, 0, 0}, {2, 1, 0}, intensity, 0.0,
                                            end / fog.eta, start, width, bins);
    EXPECT_GT(expect_bins(cube, variance, expected), 60);
}

}  // namespace femto::testing
