// transient_beams (plugins/integrators/transient_beams): transient progressive photon beams.
//  - agreement with an unbiased integrator per pixel block and time group on scenes/fog-point,
//    scenes/fog-object (transient_path) and scenes/laser-tank (transient_light), and with
//    transient_path on a lit slab of heterogeneous (ratio-tracked) medium and one whose
//    extinction differs per channel (each channel compared): a chi-square over cells whose
//    variances come from independent renders, less an allowance for the kernels' bias derived
//    from R_1 and T_1;
//  - the cube summed over time is the steady (hdrfilm) render of the same seed;
//  - a laser pulse crossing a medium of index eta is seen when eta times its path in the
//    medium says, with the closed-form single-scattering amplitude;
//  - a furnace filled with a conservative medium keeps the furnace's radiance (the split between
//    beams and path-traced surfaces counts every path once);
//  - renders are bit-identical for a seed on 1 and 2 threads;
//  - bad input is a SceneError naming the parameter and its location.
// The fixed-kernel single-scattering check is in the conformance matrix (test_integrators.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "agreement_util.h"
#include "cube_util.h"
#include "femto/error.h"
#include "femto/host.h"
#include "femto/testing/render.h"
#include "scene_util.h"
#include "vol_util.h"

using namespace femto;
using femto::test::Cube;

namespace {

constexpr double kPi = 3.14159265358979323846;

// ---- agreement on the shipped scenes ------------------------------------------------------

// One comparison of transient_beams against an unbiased reference on a shipped scene.
struct BeamsCase {
    std::string scene;
    std::vector<std::pair<std::string, std::string>> defines;  // res, bins, ...
    int spp_reference, passes;
    int block, group;          // a cell: block x block pixels, group consecutive bins
    double radius, bandwidth;  // R_1 and T_1 given to the beams
    double bin_width;          // of the film, as the defines set it
    // The share of a cell's light the kernels may move across its borders, and of the whole
    // cube's (in space; time_share() adds time's).
    double cell_space_share, total_space_share;
    std::string reference = "transient_path";
    std::string reference_children = "";
    bool hide_emitters = false;
    double resolved = 0.3, min_share = 0.0;  // which cells count (as in agreement_util.h)
};

// The bias of the beams is what their kernels do to the signal: the time kernel moves each
// contribution by at most T_1 (T_j <= T_1), the 1D blur gathers light that passes within R_1
// of a camera ray (R_j <= R_1). The time at which the blurred light is recorded is exact to
// second order in R (the closest points' offset is perpendicular to both the beam and the
// camera ray). A cell of G bins of width w can therefore gain or lose at most the light that
// arrives within T_1 of its two time borders: if its light is spread evenly over its bins, a
// share 2 T_1 / (G w) of it, and the whole cube's a share 2 T_1 / (T w) (the window's two
// ends). In space the share is the scene's (cell_space_share, total_space_share, set per
// scene below from R_1 and the pixel footprints). These are first-order bounds: the kernels
// are symmetric, so where the signal is smooth what they move out of a cell they mostly move
// back in, and the actual bias is of second order.
double time_share(double bandwidth, int bins, double bin_width) {
    return 2 * bandwidth / (bins * bin_width);
}

void check_beams_agreement(const BeamsCase& c) {
    constexpr int kRuns = 8;
    LoadOptions reference_options, beams_options;
    reference_options.defines = beams_options.defines = c.defines;
    reference_options.defines.push_back({"spp", std::to_string(c.spp_reference)});
    beams_options.defines.push_back({"spp", std::to_string(c.passes)});
    const auto reference = test::render_runs(
        test::with_integrator(c.scene, c.reference, 0, c.hide_emitters, c.reference_children),
        reference_options, kRuns, 100, "beams-ref");
    const std::string kernels =
        "<float name=\"initial_radius\" value=\"" + test::xml_number(c.radius) +
        "\"/><float name=\"initial_bandwidth\" value=\"" + test::xml_number(c.bandwidth) + "\"/>";
    const auto beams = test::render_runs(
        test::with_integrator(c.scene, "transient_beams", 0, c.hide_emitters, kernels),
        beams_options, kRuns, 200, "beams");
    const int bins = beams[0].T;
    test::expect_agree(test::cells_of(beams, c.block, c.group),
                       test::cells_of(reference, c.block, c.group), kRuns, c.scene, c.resolved,
                       c.min_share,
                       time_share(c.bandwidth, c.group, c.bin_width) + c.cell_space_share,
                       time_share(c.bandwidth, bins, c.bin_width) + c.total_space_share);
}

// A pixel's footprint at distance s from a pinhole of field of view `fov` (degrees) over
// `res` pixels.
double footprint(double s, double fov, int res) { return 2 * s * std::tan(fov * kPi / 360) / res; }

}  // namespace

// scenes/fog-point from its first light (9.75) on: the ball of fog (radius 2, seen from 10)
// lies inside the image and at least 8 from the camera. The 1D blur moves light by at most
// R_1 = 0.01 across a camera ray, at least 8 away: at most R_1 / footprint(8) pixels. A cell of
// B x B pixels loses or gains at most the light within that of its four sides, a share
// 4 R_1 / (B footprint(8)) if its light is spread evenly; the whole image loses none (the
// ball lies inside it), its border's share 4 R_1 / (16 footprint(8)) is allowed all the same.
// The first light out of the dense fog is a rare event for the path tracer, and light late in
// the window is for the short beams (few get far from the light, e^-4.1 per unit): cells must
// be resolved to 15 %, and those at the ball's rim too dim are left out (as in
// Bdpt.AgreesWithPathTracerOnFogPoint).
TEST(TransientBeams, AgreesWithPathTracerOnFogPoint) {
    BeamsCase c{"fog-point",
                {{"res", "16"}, {"start", "9.5"}, {"bins", "40"}},
                256,
                32,
                4,
                5,
                0.01,
                1e-4,
                0.1,
                0,
                0};
    c.cell_space_share = 4 * c.radius / (c.block * footprint(8, 26, 16));
    c.total_space_share = 4 * c.radius / (16 * footprint(8, 26, 16));
    c.resolved = 0.15;
    c.min_share = 0.05;
    check_beams_agreement(c);
}

// scenes/fog-object: the camera sits in the fog, so light scattered next to it is blurred over
// many pixels; there the light field is smooth (the nearest feature of the scattered light is
// the point light, 0.25 from the nearest camera ray in view, or the objects' shadows, which
// the camera rays cross, integrating the blur's two sides): a symmetric blur of R_1 then
// changes it by a share of order (R_1 / 0.25)^2. The path tracer uses equiangular connections
// (its shadow rays next to the point light have unbounded variance otherwise, as in
// Bdpt.AgreesWithPathTracerOnFogObject).
TEST(TransientBeams, AgreesWithPathTracerOnFogObject) {
    BeamsCase c{
        "fog-object", {{"res", "16"}, {"bins", "80"}}, 64, 32, 2, 8, 0.01, 5e-4, 0.05, 0, 0};
    c.cell_space_share = c.total_space_share = (c.radius / 0.25) * (c.radius / 0.25);
    c.reference_children =
        "<connection type=\"equiangular\"/><boolean name=\"mis\" value=\"true\"/>";
    c.hide_emitters = true;  // the point light in view: the path tracer never sees it
    c.resolved = 0.15;
    check_beams_agreement(c);
}

// scenes/laser-tank against the light tracer: the path tracer finds the glow on the walls only
// when a bounce off a wall happens to cross the laser, rare events that leave 4-pixel blocks
// 0.3-3x off even at 16384 samples (Bdpt.AgreesWithLightTracerOnLaserTank), while the light
// tracer, BDPT and the path tracer agree where the path tracer converges. The medium (the tank)
// is at least 41 from the camera; the blur of R_1 = 0.1 (the laser's radius is 0.8) moves
// light by at most R_1 / footprint(41) pixels: a share 4 R_1 / (B footprint(41)) of a cell; the
// image's border cuts the tank, so the whole cube may lose a share 4 R_1 / (16 footprint(41)).
// (Light gathered on the way from a wall is blurred in the directions the wall integrates over,
// not across pixels.)
TEST(TransientBeams, AgreesWithLightTracerOnLaserTank) {
    BeamsCase c{"laser-tank",
                {{"res", "16"}, {"bins", "60"}, {"bin_width", "1"}},
                64,
                32,
                4,
                10,
                0.1,
                0.01,
                1.0,
                0,
                0};
    c.cell_space_share = 4 * c.radius / (c.block * footprint(41, 45, 16));
    c.total_space_share = 4 * c.radius / (16 * footprint(41, 45, 16));
    c.reference = "transient_light";
    check_beams_agreement(c);
}

// ---- agreement in a heterogeneous and in a chromatic medium ---------------------------------

namespace {

// A slab of medium (x, y in [-2.5, 2.5], z in [-0.5, 0.5], behind null faces) between a camera
// at (0, 0, 6) looking down -z (fov 30, 16 x 16 pixels) and a diffuse wall (reflectance 0.5)
// at z = -1.5; a sphere light of radius 0.2 at (0, 1.6, 1.5), just above the view, shines on
// the slab's front face and, through the slab, on the wall. The slab and the wall fill the
// image, so no silhouette crosses it: every camera ray enters the front face and leaves by the
// back face (at incidence theta, tan theta <= sqrt(2) tan 15 = 0.38 at the image's corners),
// meets the wall, and a path that bounces there gathers beams through the slab again. The
// wall is lit only through the slab (next-event estimation through the medium). Light reaches
// the camera after 6.7 (camera time) through the slab alone and after 10.8 off the wall; the
// film's window is [6.5, 14.5] in 40 bins of 0.2. max_depth 6 for both integrators.
constexpr double kSlabDistance = 5.5;  // from the camera to the slab's front face
constexpr double kSlabFov = 30, kSlabThickness = 1;
constexpr double kSlabStart = 6.5, kSlabBinWidth = 0.2;
constexpr int kSlabRes = 16, kSlabBins = 40, kSlabDepth = 6, kSlabRuns = 8;

std::string lit_slab(const std::string& medium, const std::string& integrator, int spp) {
    return test::scene_xml(
        medium + integrator + "<sensor type=\"perspective\"><float name=\"fov\" value=\"" +
        test::xml_number(kSlabFov) +
        "\"/><transform name=\"to_world\"><lookat origin=\"0,0,6\" target=\"0,0,0\" "
        "up=\"0,1,0\"/></transform>" +
        test::independent_sampler(spp) +
        test::box_transient_film(kSlabRes, kSlabRes, kSlabStart, kSlabBinWidth, kSlabBins) +
        "</sensor><shape type=\"cube\"><transform name=\"to_world\"><scale x=\"2.5\" y=\"2.5\" "
        "z=\"0.5\"/></transform><bsdf type=\"null\"/><ref name=\"interior\" id=\"slab\"/></shape>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale x=\"2.5\" y=\"2.5\"/>"
        "<translate z=\"-1.5\"/></transform><bsdf type=\"diffuse\"><float name=\"reflectance\" "
        "value=\"0.5\"/></bsdf></shape><shape type=\"sphere\"><point name=\"center\" value=\"0, "
        "1.6, 1.5\"/><float name=\"radius\" value=\"0.2\"/><bsdf type=\"diffuse\"><float "
        "name=\"reflectance\" value=\"0\"/></bsdf><emitter type=\"area\"><rgb name=\"radiance\" "
        "value=\"20\"/></emitter></shape>");
}

// Cells of one colour channel (cells_of() sums the three).
test::Cells channel_cells(std::vector<Cube> runs, int block, int group, int channel) {
    for (Cube& cube : runs)
        for (size_t i = 0; i < cube.data.size(); ++i)
            if (int(i % size_t(cube.C)) != channel) cube.data[i] = 0.f;
    return test::cells_of(runs, block, group);
}

// One comparison on the lit slab: the medium (a <medium id="slab">), transient_path's samples
// per pixel, the beams' passes, photons per pass, R_1 and T_1, and the cells.
struct SlabCase {
    std::string what, medium;
    int spp_reference = 256, passes = 32, photons = 8192;
    double radius = 0.004, bandwidth = 0.0005;
    int block = 4, group = 5;
};

struct SlabRuns {
    std::vector<Cube> beams, reference;
};

SlabRuns render_slab(const SlabCase& c) {
    const std::string depth =
        "<integer name=\"max_depth\" value=\"" + std::to_string(kSlabDepth) + "\"/>";
    SlabRuns out;
    out.reference = test::render_runs(
        lit_slab(c.medium, "<integrator type=\"transient_path\">" + depth + "</integrator>",
                 c.spp_reference),
        {}, kSlabRuns, 100, c.what + "-ref");
    out.beams = test::render_runs(
        lit_slab(c.medium,
                 "<integrator type=\"transient_beams\">" + depth +
                     "<integer name=\"photons_per_pass\" value=\"" + std::to_string(c.photons) +
                     "\"/><float name=\"initial_radius\" value=\"" + test::xml_number(c.radius) +
                     "\"/><float name=\"initial_bandwidth\" value=\"" +
                     test::xml_number(c.bandwidth) + "\"/></integrator>",
                 c.passes),
        {}, kSlabRuns, 200, c.what + "-beams");
    return out;
}

// The kernels' bias on the lit slab, first-order bounds as for the shipped scenes above:
//  - time: a cell of G bins gains or loses at most the light within T_1 of its two time
//    borders, time_share();
//  - across pixels: the 1D blur moves light by at most R_1 across a camera ray, at least
//    kSlabDistance from the camera: R_1 / footprint(5.5) pixels, a share
//    4 R_1 / (B footprint(5.5)) of a B x B cell if its light is spread evenly over it, and of
//    the whole image (the slab reaches past the image's border, so light crosses it too);
//  - the slab's faces: beams end there, so a camera point whose blur reaches past a face
//    loses the part of the kernel beyond it: at most half the kernel, over the last
//    R_1 tan(theta) of the camera segment before the face, tan(theta) <= 0.38. The light
//    scattered toward the camera per unit length varies along a camera segment through the
//    slab by less than a factor 8 (it falls as exp(-2 sigma_t s) into the slab, optical depth
//    at most 2.2, a factor 4.4; sigma_s varies by at most 1.8 in the heterogeneous slab), and
//    the segment is at least kSlabThickness long: two faces lose at most a share
//    2 x 1/2 x R_1 0.38 x 8 / kSlabThickness of its light.
// With R_1 = 0.004 and T_1 = 0.0005 (cells of 4 x 4 pixels and 5 bins): 2.2 % + 1.2 % +
// 0.1 %, against a beams' relative error of 3-20 % per resolved cell (8 runs).
double slab_space_share(const SlabCase& c) {
    const double tan_incidence = std::sqrt(2.0) * std::tan(kSlabFov * kPi / 360);
    return 4 * c.radius / (c.block * footprint(kSlabDistance, kSlabFov, kSlabRes)) +
           c.radius * tan_incidence * 8 / kSlabThickness;
}

void expect_slab_agreement(const test::Cells& beams, const test::Cells& reference,
                           const SlabCase& c, const std::string& what) {
    test::expect_agree(beams, reference, kSlabRuns, what, 0.3, 0.0,
                       time_share(c.bandwidth, c.group, kSlabBinWidth) + slab_space_share(c),
                       time_share(c.bandwidth, kSlabBins, kSlabBinWidth) + slab_space_share(c));
}

}  // namespace

// A heterogeneous slab: density (per unit length) 1 + 0.08 (x + 2.5), a gradient across the
// image, plus a Gaussian blob 0.6 exp(-r^2 / (2 0.4^2)) around (0.3, 0.2, 0), albedo 0.8, on a
// 41 x 41 x 9 lattice over the slab. Its extinction lies in [1.0, 1.81], mean 1.22: the
// majorant 1.81, at which both integrators draw free flights, is 1.5 times the mean, and the
// residual that ratio tracking estimates (above the control 1.0) is 0.81 against a mean 0.22,
// so every Tr (the beams' Tr_b, the camera's Tr_c, the shadow rays to the wall) is a ratio-
// tracked estimate and the beams' weight exp(1.81 t_b) Tr_b(t_b) is far from 1 (its mean is
// 1 to 2.3 after a unit of length). The blob shadows the wall (its optical depth is 0.47).
// The majorant is kept below twice the smallest extinction: a free flight drawn at the
// majorant weighs Tr / exp(-majorant t), whose second moment grows as
// exp((majorant - 2 sigma_t) t); with a majorant 4.5 times the smallest extinction, the rare
// heavy weights of long beams made the 8 runs' variances unreliable (late time groups 5-8 %
// off at |z| 3-4, which 24 runs of other seeds did not reproduce).
TEST(TransientBeams, AgreesWithPathTracerInAHeterogeneousMedium) {
    const auto dir = femto::testing::temp_dir("beams-heterogeneous");
    const std::string vol = (dir / "slab.vol").string();
    const auto density = [](int i, int j, int k) {
        const double x = -2.5 + i / 8.0, y = -2.5 + j / 8.0, z = -0.5 + k / 8.0;
        const double r2 = (x - 0.3) * (x - 0.3) + (y - 0.2) * (y - 0.2) + z * z;
        return 1.0 + 0.08 * (x + 2.5) + 0.6 * std::exp(-r2 / (2 * 0.4 * 0.4));
    };
    test::write_bytes(
        vol, test::make_grid(41, 41, 9, Vec3(-2.5f, -2.5f, -0.5f), Vec3(2.5f, 2.5f, 0.5f), density)
                 .bytes());
    SlabCase c;
    c.what = "heterogeneous slab";
    c.medium = "<medium type=\"heterogeneous\" id=\"slab\"><string name=\"density\" value=\"" +
               vol + "\"/><float name=\"albedo\" value=\"0.8\"/></medium>";
    const SlabRuns runs = render_slab(c);
    std::filesystem::remove_all(dir);
    expect_slab_agreement(test::cells_of(runs.beams, c.block, c.group),
                          test::cells_of(runs.reference, c.block, c.group), c, c.what);
}

// A homogeneous slab whose extinction differs per channel: sigma_s (0.24, 0.8, 1.6), sigma_a
// (0.06, 0.2, 0.4), so sigma_t = (0.3, 1, 2), albedo 0.8. Photon paths draw their free
// flights at the channels' mean, 1.1, so a beam's weight Tr_b / P_b = exp((1.1 - sigma_t) t_b)
// is exp(0.8 t_b) in red, exp(0.1 t_b) in green and exp(-0.9 t_b) in blue: each channel is
// compared on its own.
// Sensitivity: light scattered once toward the camera a depth s into the slab has come
// about s along its beam and goes s back (the light is in front, near the camera's side), so
// its share at depth s is proportional to exp(-2 sigma_t s) on [0, 1]. Without the weight
// (Tr_b / P_b taken as 1, right only in a grey medium) a beam would bring exp(-1.1 t_b)
// instead of exp(-sigma_t t_b): the slab's light would be off by
// int exp(-2 sigma_t s) exp((sigma_t - 1.1) s) ds / int exp(-2 sigma_t s) ds - 1 =
// -28 % in red, -3 % in green, +26 % in blue; without 1 / P_b alone (Tr_b kept, exp(1.1 t_b)
// dropped) -36 %, -29 %, -21 %. Measured with the plugin so broken (same seeds and cells; the
// slab's light alone fills the cells until 10.5, the wall's is path traced): weight 1 gives
// the slab's light per time group 0.52-0.88 times the reference in red, 0.93-0.99 in green,
// 1.15-1.93 in blue, whole-cube totals -17 %, -4.1 %, +36 % (z -65, -7.3, +36) and chi2
// 12460, 158, 4787 against the bound 286: red and blue fail by far (green, whose weight
// exp(0.1 t_b) is nearly 1, stays within its tolerance); dropping exp(1.1 t_b) gives totals
// -21 %, -31 %, -24 % and chi2 above 6000 in every channel. Per cell the tolerance is the
// cells' combined standard error (median 6-7 %, 2-13 % from the 10th to the 90th percentile)
// plus the 3.5 % allowance; for the totals 4 standard errors (each 0.4-0.8 %) plus 3.4 %.
TEST(TransientBeams, AgreesWithPathTracerWithAChromaticMedium) {
    SlabCase c;
    c.what = "chromatic slab";
    c.medium =
        "<medium type=\"homogeneous\" id=\"slab\"><rgb name=\"sigma_s\" value=\"0.24, 0.8, "
        "1.6\"/><rgb name=\"sigma_a\" value=\"0.06, 0.2, 0.4\"/></medium>";
    const SlabRuns runs = render_slab(c);
    for (int channel = 0; channel < 3; ++channel)
        expect_slab_agreement(channel_cells(runs.beams, c.block, c.group, channel),
                              channel_cells(runs.reference, c.block, c.group, channel), c,
                              c.what + " channel " + std::to_string(channel));
}

// ---- the time integral is the steady render -------------------------------------------------

TEST(TransientBeams, TimeIntegralIsTheSteadyImage) {
    // scenes/laser-tank (index 1.33, walls lit through the medium, a delta light), its cube
    // summed over time against an hdrfilm of the same size, seed and passes. Both films get the
    // same beams and camera samples: photons_per_pass and R_1 depend on the film's size only,
    // T_1 only smooths time, which the bins' sum undoes whenever every kernel lies inside the
    // window: with max_depth 6 a path has at most 6 segments, each shorter than the room's
    // diagonal (70) times 1.33, 560 in all, inside [0, 800). So the two agree to float
    // rounding (the cube sums per bin in float, hdrfilm in double), not just within noise.
    LoadOptions options;
    options.defines = {
        {"res", "8"}, {"spp", "6"}, {"start", "0"}, {"bin_width", "8"}, {"bins", "100"}};
    const std::string transient = test::with_integrator("laser-tank", "transient_beams", 6, false);
    const std::string steady = test::replace_element(
        transient, "<film type=\"transient\">", "</film>",
        "<film type=\"hdrfilm\"><integer name=\"width\" value=\"$res\"/><integer name=\"height\" "
        "value=\"$res\"/><rfilter type=\"box\"/></film>");
    auto a = load_scene_string(transient, options, test::kScenes);
    auto b = load_scene_string(steady, options, test::kScenes);
    const std::vector<float> cube_sum = femto::testing::render_steady(*a, 7);
    const std::vector<float> image = femto::testing::render_steady(*b, 7);
    femto::testing::expect_same_image(cube_sum, image, "transient cube summed", "hdrfilm");
}

// ---- the delay of a slower medium ---------------------------------------------------------

namespace {

// A laser pulse through a medium of index eta: a collimated beam of radius 0.1 and power 1
// leaves x = -3 at t = 0 along +x and enters, at x = -2, a box of homogeneous medium
// (sigma_s 0.15, sigma_a 0.05, isotropic) x in [-2, 2], y and z in [-1, 1] behind null walls.
// A one-pixel orthographic camera of 0.001 x 0.001 at z = 5 looks down -z through the box's
// top at x = y = 0, across the beam. Single scattering only (max_depth 2). Light seen at depth
// z in the beam (|z| <= 0.1) has travelled 1 in vacuum, eta 2 in the medium along the beam,
// eta (1 - z) in the medium and 4 in vacuum toward the camera: it arrives at camera time
// 5 + eta (3 - z).
constexpr double kSigmaS = 0.15, kSigmaT = 0.2, kBeamRadius = 0.1;
constexpr double kDelayStart = 7.5, kDelayWidth = 0.02, kR1 = 0.01, kT1 = 0.005;
constexpr int kDelayBins = 100;

std::string laser_through_medium(double eta, int passes) {
    return test::scene_xml(
        "<medium type=\"homogeneous\" id=\"water\"><float name=\"sigma_s\" value=\"" +
        test::xml_number(kSigmaS) + "\"/><float name=\"sigma_a\" value=\"" +
        test::xml_number(kSigmaT - kSigmaS) + "\"/><float name=\"eta\" value=\"" +
        test::xml_number(eta) +
        "\"/></medium>"
        "<integrator type=\"transient_beams\"><integer name=\"max_depth\" value=\"2\"/><float "
        "name=\"initial_radius\" value=\"" +
        test::xml_number(kR1) + "\"/><float name=\"initial_bandwidth\" value=\"" +
        test::xml_number(kT1) +
        "\"/><string name=\"temporal_kernel\" value=\"box\"/></integrator>"
        "<sensor type=\"orthographic\"><float name=\"near_clip\" value=\"0\"/><transform "
        "name=\"to_world\"><scale x=\"0.001\" y=\"0.001\"/><lookat origin=\"0,0,5\" "
        "target=\"0,0,0\" up=\"0,1,0\"/></transform>" +
        test::independent_sampler(passes) +
        test::box_transient_film(1, 1, kDelayStart, kDelayWidth, kDelayBins) +
        "</sensor><shape type=\"cube\"><transform name=\"to_world\"><scale x=\"2\" y=\"1\" "
        "z=\"1\"/></transform><bsdf type=\"null\"/><ref name=\"interior\" id=\"water\"/></shape>"
        "<emitter type=\"collimated\"><transform name=\"to_world\"><lookat origin=\"-3,0,0\" "
        "target=\"0,0,0\" up=\"0,1,0\"/></transform><float name=\"radius\" value=\"" +
        test::xml_number(kBeamRadius) + "\"/><float name=\"power\" value=\"1\"/></emitter>");
}

// The time-integrated radiance the pixel sees: irradiance 1 / (pi r^2) inside the beam,
// attenuated over the 2 units the beam crosses and the 1 - z of the camera's leg, scattered
// with sigma_s / (4 pi), along the chord |z| <= c(y) = sqrt(r^2 - y^2) at height y. The
// beams see it blurred across the camera ray (along y, the direction perpendicular to both) by
// the Epanechnikov kernel of radius R: integral of K_R(y) L(y) dy (R = 0: L(0)).
double laser_radiance(double radius) {
    auto chord = [](double y) {
        const double c = std::sqrt(std::max(0.0, kBeamRadius * kBeamRadius - y * y));
        return (std::exp(kSigmaT * c) - std::exp(-kSigmaT * c)) / kSigmaT;
    };
    const double scale =
        kSigmaS / (4 * kPi) / (kPi * kBeamRadius * kBeamRadius) * std::exp(-3 * kSigmaT);
    if (radius == 0) return scale * chord(0);
    const int steps = 20000;
    double sum = 0;
    for (int i = 0; i < steps; ++i) {
        const double y = radius * (-1 + 2 * (i + 0.5) / steps);
        sum += 0.75 / radius * (1 - (y / radius) * (y / radius)) * chord(y) * 2 * radius / steps;
    }
    return scale * sum;
}

}  // namespace

TEST(TransientBeams, LaserInASlowMediumArrivesAtEtaTimesItsPath) {
    // Every contribution arrives at 5 + eta (3 - z) spread by the time kernel (a box of
    // half-width T_j <= T_1): the cube holds light only in the bins that meet
    // [5 + eta (3 - r) - T_1, 5 + eta (3 + r) + T_1], its energy-weighted mean bin centre is
    // 5 + 3 eta within half a bin (the light is symmetric in z but for the transmittance's
    // tilt, which moves the mean by eta sigma_t r^2 / 4 = 7e-4), and with eta = 1 it all moves
    // 3 (1.33 - 1) = 0.99 earlier. The amount is the closed form blurred by K_R: the expectation
    // lies between the blur with R_1 (relative bias -R_1^2 / (10 r^2) = -1e-3) and the sharp
    // L(0), within 4 standard errors over 8 seeds of 64 passes (each eta its own seeds).
    const double blurred = laser_radiance(kR1), sharp = laser_radiance(0);
    std::vector<double> means;
    for (const double eta : {1.33, 1.0}) {
        SCOPED_TRACE("eta " + std::to_string(eta));
        const uint64_t first_seed = eta == 1.0 ? 11 : 1;
        const double arrival = 5 + 3 * eta;
        const double first = 5 + eta * (3 - kBeamRadius) - kT1,
                     last = 5 + eta * (3 + kBeamRadius) + kT1;
        std::vector<double> totals;
        double outside = 0, inside = 0, weighted = 0;
        for (uint64_t seed = first_seed; seed < first_seed + 8; ++seed) {
            auto scene = load_scene_string(laser_through_medium(eta, 64));
            const Cube cube = femto::testing::render_cube(*scene, seed, "beams-delay");
            double total = 0;
            for (int t = 0; t < cube.T; ++t) {
                const double e = cube.at(0, 0, t, 0), lo = kDelayStart + t * kDelayWidth;
                total += e;
                weighted += e * (lo + kDelayWidth / 2);
                if (lo + kDelayWidth <= first - 1e-6 || lo >= last + 1e-6)
                    outside += std::abs(e);
                else
                    inside += e;
            }
            totals.push_back(total);
        }
        EXPECT_GT(inside, 0.0);
        EXPECT_EQ(outside, 0.0) << "light outside [" << first << ", " << last << "]";
        const double mean_time = weighted / inside;
        means.push_back(mean_time);
        EXPECT_NEAR(mean_time, arrival, kDelayWidth / 2);
        const femto::testing::MeanAndError m = femto::testing::mean_and_error(totals);
        std::printf(
            "eta %.2f: mean arrival %.4f (expected %.4f), light in [%.3f, %.3f]; "
            "radiance %.6g +- %.2g (closed form %.6g sharp, %.6g blurred by R_1)\n",
            eta, mean_time, arrival, first, last, m.mean, m.standard_error, sharp, blurred);
        EXPECT_GT(m.mean, blurred - 4 * m.standard_error);
        EXPECT_LT(m.mean, sharp + 4 * m.standard_error);
        EXPECT_LT(m.standard_error, 0.02 * sharp) << "too noisy to see the amplitude";
    }
    EXPECT_NEAR(means[0] - means[1], 0.99, kDelayWidth);
}

// ---- a furnace filled with a conservative medium --------------------------------------------

namespace {

// A closed diffuse sphere of albedo 0.5 and radius 3 emitting radiance 1 everywhere, filled with
// a medium that scatters without absorbing (sigma_s 0.2, isotropic), seen from its centre
// through a steady film. (The normals point inward, toward the medium: its `exterior`.)
constexpr double kFurnaceAlbedo = 0.5, kFurnaceSigmaS = 0.2, kFurnaceR1 = 0.02;

std::string fogged_furnace(int photons, int spp) {
    return test::scene_xml(
        "<medium type=\"homogeneous\" id=\"fog\"><float name=\"sigma_s\" value=\"" +
        test::xml_number(kFurnaceSigmaS) +
        "\"/><float name=\"sigma_a\" value=\"0\"/></medium><integrator "
        "type=\"transient_beams\"><integer name=\"photons_per_pass\" "
        "value=\"" +
        std::to_string(photons) + "\"/><float name=\"initial_radius\" value=\"" +
        test::xml_number(kFurnaceR1) +
        "\"/></integrator><sensor type=\"perspective\"><float name=\"fov\" value=\"60\"/><ref "
        "id=\"fog\"/>" +
        test::independent_sampler(spp) +
        "<film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" "
        "value=\"16\"/><rfilter type=\"box\"/></film></sensor><shape type=\"sphere\"><float "
        "name=\"radius\" value=\"3\"/><boolean name=\"flip_normals\" value=\"true\"/><bsdf "
        "type=\"diffuse\"><float name=\"reflectance\" value=\"" +
        test::xml_number(kFurnaceAlbedo) +
        "\"/></bsdf><emitter type=\"area\"><float name=\"radiance\" value=\"1\"/></emitter><ref "
        "name=\"exterior\" id=\"fog\"/></shape>");
}

}  // namespace

TEST(TransientBeams, FurnaceWithAConservativeMediumKeepsItsRadiance) {
    // Inside the emitting sphere L = Le / (1 - albedo) = 2 in every direction at every point;
    // a medium that only scatters leaves that uniform, isotropic field unchanged (what it
    // scatters out of a ray it scatters back in). The camera paths split it: the beams estimate
    // all light scattered toward the camera in the medium, 1 - e^(-0.2 x 3) = 45 % of it, the
    // path tracer what reaches the camera from the walls through the medium's transmittance.
    // The image mean is 2 only if every path is counted once, by one side, with its power.
    // Kernel bias: the beams' density is uniform and isotropic, so the 1D blur adds none
    // except within R_1 of the wall, where the beams end: at most a share R_1 / 3 of the
    // camera segment's in-scattered light, taken as the allowance. Every pixel of a pass
    // shares its beams, so the error comes from 8 independent renders.
    const double expected = 1.0 / (1.0 - kFurnaceAlbedo);
    std::vector<double> means;
    for (uint64_t seed = 1; seed <= 8; ++seed) {
        auto scene = load_scene_string(fogged_furnace(2048, 8));
        means.push_back(
            femto::testing::pixel_mean(femto::testing::render_steady(*scene, seed), 1).mean);
    }
    const femto::testing::MeanAndError m = femto::testing::mean_and_error(means);
    std::printf("furnace: %.5f +- %.5f (expected %.5f)\n", m.mean, m.standard_error, expected);
    EXPECT_GT(m.standard_error, 0.0);
    EXPECT_LT(m.standard_error, 0.01 * expected) << "too noisy to see a missing share";
    EXPECT_NEAR(m.mean, expected, 4 * m.standard_error + kFurnaceR1 / 3 * expected)
        << "standard error " << m.standard_error;
}

// ---- determinism -----------------------------------------------------------------------------

namespace {

// The cube of `xml` rendered with seed 3 on `threads` threads.
Cube cube_with_threads(const std::string& xml, const LoadOptions& options, int threads) {
    auto scene = load_scene_string(xml, options, test::kScenes);
    RenderOptions opt;
    opt.threads = threads;
    opt.seed = 3;
    const RenderStats stats = render(*scene, opt);
    RenderInfo info = make_render_info(*scene, opt, stats);
    info.write_npy = true;
    const auto dir = femto::testing::temp_dir("beams-threads-" + std::to_string(threads));
    scene->sensor().film().write((dir / "cube").string(), info);
    Cube cube = femto::testing::read_npy((dir / "cube.npy").string());
    std::filesystem::remove_all(dir);
    return cube;
}

}  // namespace

TEST(TransientBeams, SameCubeOnOneAndTwoThreads) {
    // Photon paths are traced in fixed chunks of 1024 and their beams appended in chunk order;
    // the beams a camera ray finds are summed in index order, whatever the hierarchy Embree
    // builds: the cube does not depend on the thread count, to the bit. (fog-object at 48 x 48
    // pixels: 2304 photon paths per pass by default, three chunks; its objects bring the
    // path-traced surfaces in.)
    LoadOptions options;
    options.defines = {{"res", "48"}, {"spp", "3"}, {"bins", "40"}};
    const std::string xml = test::with_integrator("fog-object", "transient_beams", 0, false);
    const Cube one = cube_with_threads(xml, options, 1);
    const Cube two = cube_with_threads(xml, options, 2);
    ASSERT_EQ(one.data.size(), two.data.size());
    double total = 0;
    size_t differ = 0;
    for (size_t i = 0; i < one.data.size(); ++i) {
        total += one.data[i];
        if (one.data[i] != two.data[i] && ++differ <= 5)
            ADD_FAILURE() << "value " << i << ": 1 thread " << one.data[i] << ", 2 threads "
                          << two.data[i];
    }
    EXPECT_EQ(differ, 0u);
    EXPECT_GT(total, 0.0);
}

// ---- bad input -------------------------------------------------------------------------------

namespace {

// A ball of fog lit by a point light, with `integrator`'s children and `film` each on lines of
// their own.
std::string fog_ball(const std::string& children, const std::string& film, bool medium = true) {
    return "<scene version=\"3.0.0\">\n" +
           std::string(medium ? "<medium type=\"homogeneous\" id=\"fog\"/>\n" : "") +
           "<integrator type=\"transient_beams\">\n" + children +
           "\n</integrator>\n<sensor type=\"perspective\"><transform name=\"to_world\"><lookat "
           "origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/></transform>\n" +
           test::independent_sampler(1) + "\n" + film + "\n</sensor>\n<shape type=\"sphere\">" +
           (medium ? "<bsdf type=\"null\"/><ref name=\"interior\" id=\"fog\"/>" : "") +
           "</shape>\n<emitter type=\"point\"><point name=\"position\" value=\"0,2,0\"/>"
           "</emitter>\n</scene>\n";
}

std::string film(const std::string& extra, const std::string& tfilter = "histogram") {
    return "<film type=\"transient\"><integer name=\"width\" value=\"4\"/><integer "
           "name=\"height\" value=\"4\"/><float name=\"bin_width\" value=\"0.1\"/><integer "
           "name=\"bins\" value=\"100\"/>" +
           extra + "\n<tfilter type=\"" + tfilter + "\"/>\n</film>";
}

// The 1-based line of `xml` on which `text` starts.
int line_of(const std::string& xml, const std::string& text) {
    const size_t at = xml.find(text);
    EXPECT_NE(at, std::string::npos) << text;
    return 1 + int(std::count(xml.begin(), xml.begin() + std::ptrdiff_t(at), '\n'));
}

// Loads and renders `xml`; expects a SceneError mentioning `message` located in the scene
// text at the line where `where` starts.
void expect_scene_error(const std::string& xml, const std::string& message,
                        const std::string& where) {
    SCOPED_TRACE(message);
    try {
        auto scene = load_scene_string(xml);
        femto::testing::render_steady(*scene, 1);
        ADD_FAILURE() << "accepted:\n" << xml;
    } catch (const SceneError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(message), std::string::npos) << what;
        EXPECT_EQ(what.rfind("<string>:" + std::to_string(line_of(xml, where)) + ":", 0), 0u)
            << "not located at \"" << where << "\": " << what;
    }
}

}  // namespace

TEST(TransientBeams, RefusesBadParametersWithTheirLocation) {
    const std::pair<std::string, std::string> cases[] = {
        {"<float name=\"initial_radius\" value=\"0\"/>", "initial_radius must be positive"},
        {"<float name=\"initial_radius\" value=\"-1\"/>", "initial_radius must be positive"},
        {"<float name=\"initial_bandwidth\" value=\"0\"/>", "initial_bandwidth must be positive"},
        {"<float name=\"initial_bandwidth\" value=\"nan\"/>", "initial_bandwidth"},
        {"<float name=\"alpha\" value=\"0\"/>", "alpha must lie in (0, 1)"},
        {"<float name=\"alpha\" value=\"1\"/>", "alpha must lie in (0, 1)"},
        {"<float name=\"alpha\" value=\"-0.5\"/>", "alpha must lie in (0, 1)"},
        {"<float name=\"beta_t\" value=\"-0.1\"/>", "beta_t must lie in [0, 1]"},
        {"<float name=\"beta_t\" value=\"1.5\"/>", "beta_t must lie in [0, 1]"},
        {"<integer name=\"photons_per_pass\" value=\"0\"/>", "photons_per_pass must lie in"},
        {"<integer name=\"photons_per_pass\" value=\"-5\"/>", "photons_per_pass must lie in"},
        {"<integer name=\"photons_per_pass\" value=\"100000000\"/>",
         "photons_per_pass must lie in"},
        {"<string name=\"spatial_kernel\" value=\"cone\"/>", "unknown kernel \"cone\""},
        {"<string name=\"temporal_kernel\" value=\"cone\"/>", "unknown kernel \"cone\""},
    };
    for (const auto& [xml, message] : cases) {
        // Each parameter on a line of its own, after a valid one: the error names that line.
        expect_scene_error(fog_ball("<integer name=\"max_depth\" value=\"8\"/>\n" + xml, film("")),
                           message, xml);
    }
    // The edges of the ranges are accepted.
    for (const std::string xml :
         {"<float name=\"beta_t\" value=\"0\"/>", "<float name=\"beta_t\" value=\"1\"/>",
          "<integer name=\"photons_per_pass\" value=\"1\"/>"}) {
        auto scene = load_scene_string(fog_ball(xml, film("")));
        EXPECT_NO_THROW(femto::testing::render_steady(*scene, 1)) << xml;
    }
}

TEST(TransientBeams, RefusesScenesItCannotRender) {
    // No medium: nothing for the beams to estimate (located at the integrator).
    expect_scene_error(fog_ball("", film(""), false), "this scene has none",
                       "<integrator type=\"transient_beams\">");
    // A kernel temporal filter would smooth time a second time, whether T_1 is the default or
    // given (located at the filter).
    for (const std::string bandwidth : {"", "<float name=\"initial_bandwidth\" value=\"0.1\"/>"})
        expect_scene_error(fog_ball(bandwidth, film("", "kernel")), "<tfilter type=\"histogram\"/>",
                           "<tfilter type=\"kernel\"/>");
    // World time removes one sensor distance per camera sample while the beams add light from
    // every point of the camera ray (located at the integrator).
    expect_scene_error(fog_ball("", film("<boolean name=\"world_time\" value=\"true\"/>")),
                       "world_time=false", "<integrator type=\"transient_beams\">");
}
