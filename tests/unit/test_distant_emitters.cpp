// Distant emitters (directional, constant, envmap): closed forms for what they light, their
// time convention (plane waves from the scene sphere's tangent plane, docs/distant-light.md),
// the envmap's mapping and sampling, agreement between integrators, and bad input.
//
// Tolerances: deterministic renders (a delta light and one bounce) agree to float rounding
// (1e-5 relative). Monte Carlo means lie within 5 standard errors, estimated from the spread
// of independent pixels or runs of equal expectation.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "chi2.h"
#include "femto/emitter.h"
#include "femto/error.h"
#include "femto/host.h"
#include "femto/image_io.h"
#include "femto/scene.h"
#include "femto/testing/render.h"
#include "femto/transform.h"
#include "scene_util.h"
#include "shape_test_util.h"

namespace {

using femto::Color;
using femto::Vec2;
using femto::Vec3;
using femto::test::independent_sampler;
using femto::test::load_error;
using femto::test::xml_number;
using femto::testing::MeanAndError;

constexpr double kPiD = 3.14159265358979323846;

// An orthographic camera at height 5 above the origin looking down -z at [-1, 1]^2, `res`^2
// pixels, each pixel's samples its own (box filter).
std::string ortho_camera(int res, int spp, const std::string& film = "hdrfilm",
                         const std::string& film_extra = "") {
    return "<sensor type=\"orthographic\"><transform name=\"to_world\"><lookat origin=\"0,0,5\" "
           "target=\"0,0,0\" up=\"0,1,0\"/></transform>" +
           independent_sampler(spp) + "<film type=\"" + film +
           "\"><integer name=\"width\" value=\"" + std::to_string(res) +
           "\"/><integer name=\"height\" value=\"" + std::to_string(res) + "\"/>" + film_extra +
           "<rfilter type=\"box\"/></film></sensor>";
}

// The plane z = 0 over [-2, 2]^2, diffuse of reflectance `albedo`.
std::string ground(double albedo) {
    return "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"2\"/>"
           "</transform><bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"" +
           xml_number(albedo) + "\"/></bsdf></shape>";
}

std::string directional(const Vec3& travel, double irradiance) {
    return "<emitter type=\"directional\"><vector name=\"direction\" x=\"" + xml_number(travel.x) +
           "\" y=\"" + xml_number(travel.y) + "\" z=\"" + xml_number(travel.z) +
           "\"/><float name=\"irradiance\" value=\"" + xml_number(irradiance) + "\"/></emitter>";
}

std::string integrator(const std::string& type, const std::string& body = "") {
    return "<integrator type=\"" + type + "\">" + body + "</integrator>";
}

std::string scene(const std::string& body) {
    return "<scene version=\"3.0.0\">" + body + "</scene>";
}

// ---- directional ---------------------------------------------------------------------------

// A diffuse plane under a directional light at 60 degrees reflects rho / pi E cos(60) toward
// every direction; the light sample is a delta and the one bounce leaves the scene, so every
// pixel holds exactly that, for the integrators that sample lights at surfaces.
TEST(DistantLight, DirectionalFollowsTheCosineLaw) {
    const double theta = 60 * kPiD / 180, rho = 0.5, E = 3.0;
    const Vec3 travel(-float(std::sin(theta)), 0.f, -float(std::cos(theta)));
    const double expected = rho / kPiD * E * std::cos(theta);
    for (const std::string type : {"direct", "path", "transient_path"}) {
        auto s = femto::load_scene_string(scene(
            integrator(type, type == "direct" ? "" : "<integer name=\"max_depth\" value=\"4\"/>") +
            ortho_camera(8, 4) + ground(rho) + directional(travel, E)));
        const std::vector<float> img = femto::testing::render_steady(*s, 1);
        for (size_t i = 0; i < img.size(); ++i)
            ASSERT_NEAR(img[i], expected, 1e-5 * expected) << type << " value " << i;
    }
}

// The plane wave crosses the scene sphere's tangent plane at time 0, so the light reaches the
// ground point x after R - dot(x - c, wi) and the camera 5 later: per pixel, the energy-
// weighted mean time is that at the pixel's centre (the time is linear across the pixel).
TEST(DistantLight, DirectionalArrivesAsAPlaneWave) {
    const double theta = 40 * kPiD / 180;
    const Vec3 wi(float(std::sin(theta)), 0.f, float(std::cos(theta)));
    const int res = 8, spp = 64, bins = 800;
    const double start = 0.0, width = 0.025;
    const std::string film_extra =
        "<float name=\"start\" value=\"0\"/><float name=\"bin_width\" "
        "value=\"0.025\"/><integer name=\"bins\" value=\"800\"/>";
    auto s = femto::load_scene_string(scene(integrator("transient_path") +
                                            ortho_camera(res, spp, "transient", film_extra) +
                                            ground(0.5) + directional(-wi, 1.0)));
    const femto::SceneSphere& sphere = s->sphere();
    // The sphere holds the ground ([-2, 2]^2) and the camera (0, 0, 5).
    EXPECT_GE(sphere.radius, 0.5 * std::sqrt(16.0 + 16.0 + 25.0));
    const femto::testing::Cube cube = femto::testing::render_cube(*s, 5, "plane-wave");
    ASSERT_EQ(cube.T, bins);
    const double pixel = 2.0 / res;
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) {
            const Vec3 centre(float(-1 + (x + 0.5) * pixel), float(1 - (y + 0.5) * pixel), 0.f);
            const double expected = 5.0 + sphere.plane_wave_distance(centre, wi);
            double e = 0, et = 0;
            for (int t = 0; t < bins; ++t) {
                e += cube.energy(y, x, t);
                et += cube.energy(y, x, t) * (start + (t + 0.5) * width);
            }
            ASSERT_GT(e, 0) << x << "," << y;
            // Binning moves each sample by at most half a bin; the samples' spread across the
            // pixel (sin(theta) pixel / sqrt(12)) leaves a standard error of that / sqrt(spp).
            const double tolerance =
                0.5 * width + 5 * std::sin(theta) * pixel / std::sqrt(12.0 * spp);
            EXPECT_NEAR(et / e, expected, tolerance) << "pixel " << x << "," << y;
        }
}

// ---- constant ------------------------------------------------------------------------------

// A diffuse sphere of albedo rho in a constant environment L (a furnace): a convex body sees the
// environment over every point's whole hemisphere, so it reflects rho L; around it the camera
// sees L. Pixels wholly on the sphere are independent estimates of rho L.
void expect_furnace(const std::string& environment, double L, const std::string& what) {
    const int res = 16, spp = 64;
    const double rho = 0.6, radius = 0.5;
    auto s = femto::load_scene_string(
        scene(integrator("path") + ortho_camera(res, spp) +
              "<shape type=\"sphere\"><float name=\"radius\" value=\"0.5\"/><bsdf "
              "type=\"diffuse\"><float name=\"reflectance\" value=\"0.6\"/></bsdf></shape>" +
              environment),
        {}, femto::testing::temp_dir("furnace").string());
    const std::vector<float> img = femto::testing::render_steady(*s, 2);
    std::vector<double> on_sphere;
    const double pixel = 2.0 / res, half_diagonal = pixel * std::sqrt(0.5);
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) {
            const double cx = -1 + (x + 0.5) * pixel, cy = 1 - (y + 0.5) * pixel;
            const double r = std::hypot(cx, cy);
            const float v = img[3 * size_t(y * res + x) + 1];
            if (r + half_diagonal < radius) on_sphere.push_back(v);
            if (r - half_diagonal > radius) {
                EXPECT_NEAR(v, L, 1e-5 * L) << what << " background";
            }
        }
    ASSERT_GT(on_sphere.size(), 20u);
    const MeanAndError m = femto::testing::mean_and_error(on_sphere);
    EXPECT_NEAR(m.mean, rho * L, 5 * m.standard_error + 1e-6)
        << what << ": " << m.mean << " +- " << m.standard_error;
    EXPECT_LT(m.standard_error, 0.02 * rho * L) << what;  // the test can tell a wrong answer
}

TEST(DistantLight, ConstantEnvironmentFurnace) {
    expect_furnace("<emitter type=\"constant\"><rgb name=\"radiance\" value=\"2\"/></emitter>", 2,
                   "constant");
}

// ---- envmap --------------------------------------------------------------------------------

// Writes a W x H RGB EXR (rows from the top) into `dir`.
std::string write_envmap(const std::filesystem::path& dir, int w, int h,
                         const std::vector<float>& rgb, const std::string& name = "env.exr") {
    const std::string path = (dir / name).string();
    femto::io::write_exr_rgb(path, w, h, rgb.data(), {});
    return path;
}

std::shared_ptr<femto::Emitter> make_envmap(const std::string& path,
                                            const femto::Transform& to_world = femto::Transform()) {
    femto::Properties props("envmap", {});
    props.set_string("filename", path);
    props.set_transform("to_world", to_world);
    auto e = femto_shape_test::make_emitter(props);
    femto::SceneSphere sphere;
    sphere.center = Vec3(0.f);
    sphere.radius = 3.f;
    e->set_scene_sphere(sphere);
    return e;
}

// A map whose pixels all differ, with a bright patch, so that the tests see the orientation.
std::vector<float> patterned_map(int w, int h) {
    std::vector<float> rgb(size_t(w) * size_t(h) * 3);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i)
            for (int c = 0; c < 3; ++c)
                rgb[(size_t(j) * size_t(w) + size_t(i)) * 3 + size_t(c)] =
                    0.1f + 0.05f * float(i) + 0.3f * float(j) + 0.2f * float(c) +
                    ((i == 2 && j == 1) ? 20.f : 0.f);
    return rgb;
}

// Mitsuba 3's mapping: pixel column i at u = (i + 0.5) / W, row j at v = j / (H - 1), direction
// (sin(2 pi u) sin(pi v), cos(pi v), -cos(2 pi u) sin(pi v)) in the map's frame; radiance at a
// pixel's direction is that pixel's value.
TEST(DistantLight, EnvmapMapsPixelsAsMitsuba) {
    const int w = 8, h = 5;
    const auto dir = femto::testing::temp_dir("envmap-mapping");
    const std::vector<float> rgb = patterned_map(w, h);
    const std::string path = write_envmap(dir, w, h, rgb);
    const femto::Transform turn = femto::Transform::rotate(Vec3(0, 1, 0), 90);
    for (const femto::Transform& to_world : {femto::Transform(), turn}) {
        const auto env = make_envmap(path, to_world);
        for (int j = 1; j < h - 1; ++j)  // the first and last rows are the poles
            for (int i = 0; i < w; ++i) {
                const double u = (i + 0.5) / w, v = double(j) / (h - 1);
                const double phi = 2 * kPiD * u, theta = kPiD * v;
                const Vec3 local(float(std::sin(phi) * std::sin(theta)), float(std::cos(theta)),
                                 float(-std::cos(phi) * std::sin(theta)));
                const Color L = env->eval_environment(to_world.vector(local));
                for (int c = 0; c < 3; ++c)
                    EXPECT_NEAR(L[c], rgb[(size_t(j) * w + size_t(i)) * 3 + size_t(c)], 2e-4)
                        << "pixel " << i << "," << j << " channel " << c;
            }
        // The zenith is the whole first row's... value at u's column: check the pole is row 0.
        const Color top = env->eval_environment(to_world.vector(Vec3(0, 1, 0)));
        EXPECT_NEAR(top[0], rgb[0] * 0.5f + rgb[(w - 1) * 3] * 0.5f, 0.05f * top[0] + 0.2f);
    }
}

// sample_direct() draws directions with the density pdf_environment() reports, and its weight
// is radiance / pdf.
TEST(DistantLight, EnvmapSamplingMatchesItsPdf) {
    const int w = 16, h = 9;
    const auto dir = femto::testing::temp_dir("envmap-chi2");
    const std::string path = write_envmap(dir, w, h, patterned_map(w, h));
    const auto env = make_envmap(path, femto::Transform::rotate(Vec3(1, 0, 0), 30));
    femto_test::Chi2Options o;
    o.x0 = -1, o.x1 = 1, o.y0 = 0, o.y1 = 2 * femto_test::kPi, o.nx = 32, o.ny = 64;
    o.samples = 1'000'000;
    o.seed = femto_test::seed_from_name("EnvmapSamplingMatchesItsPdf");
    double worst_weight = 0;
    const auto result = femto_test::chi2_test(
        o,
        [&](femto::Pcg32& rng) -> std::optional<std::pair<double, double>> {
            const Vec2 u(rng.next_float(), rng.next_float());
            const femto::EmitterSample es = env->sample_direct(Vec3(0.f), u);
            if (!(es.pdf > 0)) return std::nullopt;
            const Color expected = env->eval_environment(es.wi) / es.pdf;
            for (int c = 0; c < 3; ++c)
                worst_weight = std::max(worst_weight, std::abs(double(es.weight[c] - expected[c])) /
                                                          double(expected[c]));
            return femto_test::sphere_coords(es.wi);
        },
        [&](double z, double phi) {
            return double(env->pdf_environment(femto_test::sphere_direction(z, phi)));
        });
    EXPECT_TRUE(result.error.empty()) << result.describe();
    EXPECT_GT(result.p_value, 0.01) << result.describe();
    EXPECT_NEAR(result.pdf_integral, 1.0, 1e-3) << result.describe();
    EXPECT_LT(worst_weight, 1e-5);
}

// The irradiance of an upward-facing plane under the map, E = integral of L cos over the upper
// hemisphere (by quadrature of the map's radiance), against a render of a diffuse ground seen
// from above: rho / pi E per pixel.
TEST(DistantLight, EnvmapIrradianceOfAPlane) {
    const int w = 16, h = 9;
    const auto dir = femto::testing::temp_dir("envmap-irradiance");
    write_envmap(dir, w, h, patterned_map(w, h));
    // The map's +y (zenith) turned to +z, the ground's normal.
    const femto::Transform to_world = femto::Transform::rotate(Vec3(1, 0, 0), 90);
    const auto env = make_envmap((dir / "env.exr").string(), to_world);
    const double E = femto_test::integrate_2d(
        [&](double z, double phi) {
            return double(env->eval_environment(femto_test::sphere_direction(z, phi))[1]) * z;
        },
        0, 1, 0, 2 * femto_test::kPi, 1e-6, 1e-6);
    const double rho = 0.5;
    const std::string body =
        integrator("direct") + ortho_camera(16, 32) + ground(rho) +
        "<emitter type=\"envmap\"><string name=\"filename\" value=\"env.exr\"/><transform "
        "name=\"to_world\"><rotate x=\"1\" angle=\"90\"/></transform></emitter>";
    auto s = femto::load_scene_string(scene(body), {}, dir.string());
    const MeanAndError m = femto::testing::pixel_mean(femto::testing::render_steady(*s, 3), 1);
    EXPECT_NEAR(m.mean, rho / kPiD * E, 5 * m.standard_error)
        << m.mean << " +- " << m.standard_error << " against " << rho / kPiD * E;
    EXPECT_LT(m.standard_error, 0.01 * rho / kPiD * E);
}

// A map of one value is the constant environment of that radiance.
TEST(DistantLight, UniformEnvmapIsAFurnace) {
    const auto dir = femto::testing::temp_dir("envmap-furnace");
    write_envmap(dir, 4, 3, std::vector<float>(4 * 3 * 3, 1.5f));
    // expect_furnace() loads from its own folder: give the map by its full path.
    expect_furnace("<emitter type=\"envmap\"><string name=\"filename\" value=\"" +
                       (dir / "env.exr").string() + "\"/></emitter>",
                   1.5, "envmap");
}

// ---- agreement between integrators ---------------------------------------------------------

// Mean of the image over `runs` independent renders, and its standard error.
MeanAndError image_mean(const std::string& xml, int runs, const std::string& dir = ".") {
    std::vector<double> means;
    for (int r = 0; r < runs; ++r) {
        auto s = femto::load_scene_string(xml, {}, dir);
        const std::vector<float> img = femto::testing::render_steady(*s, 100 + uint64_t(r));
        double sum = 0;
        for (float v : img) sum += v;
        means.push_back(sum / double(img.size()));
    }
    return femto::testing::mean_and_error(means);
}

// A diffuse box on the ground under a directional light and a constant sky, seen in
// perspective: light paths from the distant emitters (the light tracer's) and camera paths
// (the path tracer's, without the sky seen directly, which light paths cannot connect to)
// render the same image; BDPT, which combines both and sees the sky, renders the path
// tracer's image with the sky.
TEST(DistantLight, LightPathsAgreeWithCameraPaths) {
    const std::string camera =
        "<sensor type=\"perspective\"><float name=\"fov\" value=\"50\"/><transform "
        "name=\"to_world\"><lookat origin=\"0,-6,4\" target=\"0,0,0\" up=\"0,0,1\"/></transform>" +
        independent_sampler(16) +
        "<film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" "
        "value=\"16\"/></film></sensor>";
    const std::string box =
        "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"0.5\"/>"
        "<translate z=\"0.5\"/></transform><bsdf type=\"diffuse\"/></shape>";
    const std::string sun = directional(Vec3(-0.3f, 0.4f, -0.866f), 2.0);
    const std::string sky =
        "<emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.3\"/></emitter>";
    const std::string depth = "<integer name=\"max_depth\" value=\"3\"/>";
    const int runs = 12;
    const std::string lit = camera + ground(0.5) + box;
    const MeanAndError path = image_mean(
        scene(integrator("path", depth + "<boolean name=\"hide_emitters\" value=\"true\"/>") + lit +
              sun + sky),
        runs);
    const MeanAndError light =
        image_mean(scene(integrator("transient_light", depth) + lit + sun + sky), runs);
    EXPECT_NEAR(light.mean, path.mean, 5 * std::hypot(light.standard_error, path.standard_error))
        << "light tracer " << light.mean << " +- " << light.standard_error << ", path " << path.mean
        << " +- " << path.standard_error;
    const MeanAndError path_sun =
        image_mean(scene(integrator("path", depth) + lit + sun + sky), runs);
    const MeanAndError bdpt =
        image_mean(scene(integrator("transient_bdpt", depth) + lit + sun + sky), runs);
    EXPECT_NEAR(bdpt.mean, path_sun.mean,
                5 * std::hypot(bdpt.standard_error, path_sun.standard_error))
        << "bdpt " << bdpt.mean << " +- " << bdpt.standard_error << ", path " << path_sun.mean
        << " +- " << path_sun.standard_error;
    EXPECT_LT(path.standard_error, 0.01 * path.mean);
}

// BDPT's weights for an environment's paths sum to one: paths of 1 and 2 segments under a
// patterned envmap, each strategy (s, t) alone and unweighted, estimate the same image as all
// of them weighted. The environment's light vertex is a direction (its densities are solid
// angles, the next vertex takes the start disk's area density) and never joins the camera
// (s = 1, t = 1 is not a strategy of these paths). Means over independent runs.
TEST(DistantLight, BdptStrategiesUnderAnEnvironmentAgree) {
    const auto dir = femto::testing::temp_dir("envmap-bdpt");
    write_envmap(dir, 16, 9, patterned_map(16, 9));
    const std::string camera =
        "<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/><transform "
        "name=\"to_world\"><lookat origin=\"0,-5,3\" target=\"0,0,0.3\" up=\"0,0,1\"/>"
        "</transform>" +
        independent_sampler(16) +
        "<film type=\"hdrfilm\"><integer name=\"width\" value=\"12\"/><integer "
        "name=\"height\" value=\"12\"/></film></sensor>";
    const std::string world =
        camera + ground(0.5) +
        "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"0.5\"/><translate "
        "z=\"0.5\"/></transform><bsdf type=\"diffuse\"/></shape><emitter type=\"envmap\"><string "
        "name=\"filename\" value=\"env.exr\"/><transform name=\"to_world\"><rotate x=\"1\" "
        "angle=\"90\"/></transform></emitter>";
    const auto bdpt = [&](int length, int s) {
        std::string body =
            "<integer name=\"path_length\" value=\"" + std::to_string(length) + "\"/>";
        if (s >= 0)
            body = "<integer name=\"strategy_s\" value=\"" + std::to_string(s) +
                   "\"/><integer name=\"strategy_t\" value=\"" + std::to_string(length + 1 - s) +
                   "\"/>";
        body += "<integer name=\"max_depth\" value=\"" + std::to_string(length) + "\"/>";
        return image_mean(scene(integrator("transient_bdpt", body) + world), 12, dir.string());
    };
    for (const int length : {1, 2}) {
        const MeanAndError weighted = bdpt(length, -1);
        EXPECT_GT(weighted.mean, 0.0);
        for (int s = 0; s <= length; ++s) {
            if (s == 1 && length == 1) continue;  // the environment never joins the camera
            const MeanAndError alone = bdpt(length, s);
            EXPECT_NEAR(alone.mean, weighted.mean,
                        5 * std::hypot(alone.standard_error, weighted.standard_error))
                << "length " << length << ", s = " << s << ": " << alone.mean << " +- "
                << alone.standard_error << " against all weighted " << weighted.mean << " +- "
                << weighted.standard_error;
        }
    }
}

// Photon mapping under a directional light: the ground's irradiance is uniform, where the
// density estimate has no bias, so a pixel holds rho / pi E cos(theta) within its noise
// (independent runs: photons are shared between a pass's pixels).
TEST(DistantLight, PhotonMappingUnderADirectionalLight) {
    const double theta = 30 * kPiD / 180, rho = 0.5, E = 1.0;
    const Vec3 travel(-float(std::sin(theta)), 0.f, -float(std::cos(theta)));
    const std::string body = integrator("transient_ppm",
                                        "<integer name=\"max_depth\" value=\"2\"/><integer "
                                        "name=\"photons_per_pass\" value=\"16384\"/>") +
                             ortho_camera(4, 16) + ground(rho) + directional(travel, E);
    const MeanAndError m = image_mean(scene(body), 10);
    const double expected = rho / kPiD * E * std::cos(theta);
    EXPECT_NEAR(m.mean, expected, 5 * m.standard_error)
        << m.mean << " +- " << m.standard_error << " against " << expected;
    EXPECT_LT(m.standard_error, 0.05 * expected);
}

// Photon beams in a fog cube under the sun and a constant sky (single scattering: paths of 2
// segments): the beams start on the distant emitters' disk and the camera sees the sky through
// the fog; the image agrees with the path tracer's. Means over independent runs; the beams'
// blur is no bias here (the lighting inside the fog varies slowly over a beam radius) except
// at the cube's faces, which the 5 standard errors leave room for.
TEST(DistantLight, PhotonBeamsUnderTheSunAndSky) {
    const std::string body =
        "<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/><transform "
        "name=\"to_world\"><lookat origin=\"0,-5,1\" target=\"0,0,0.5\" up=\"0,0,1\"/>"
        "</transform>" +
        independent_sampler(16) +
        "<film type=\"hdrfilm\"><integer name=\"width\" value=\"12\"/><integer "
        "name=\"height\" value=\"12\"/></film></sensor><medium type=\"homogeneous\" "
        "id=\"fog\"><float name=\"sigma_t\" value=\"0.5\"/><rgb name=\"albedo\" "
        "value=\"0.8\"/></medium><shape type=\"cube\"><transform name=\"to_world\"><scale "
        "value=\"0.8\"/><translate z=\"0.8\"/></transform><bsdf type=\"null\"/><ref "
        "name=\"interior\" id=\"fog\"/></shape>" +
        directional(Vec3(-0.3f, 0.4f, -0.866f), 2.0) +
        "<emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.3\"/></emitter>";
    const std::string depth = "<integer name=\"max_depth\" value=\"2\"/>";
    const MeanAndError path = image_mean(scene(integrator("path", depth) + body), 12);
    const MeanAndError beams = image_mean(scene(integrator("transient_beams", depth) + body), 12);
    EXPECT_NEAR(beams.mean, path.mean, 5 * std::hypot(beams.standard_error, path.standard_error))
        << "beams " << beams.mean << " +- " << beams.standard_error << ", path " << path.mean
        << " +- " << path.standard_error;
    EXPECT_LT(path.standard_error, 0.01 * path.mean);
}

// ---- time-integrated == steady -------------------------------------------------------------

TEST(DistantLight, TimeIntegralIsTheSteadyImage) {
    const auto dir = femto::testing::temp_dir("envmap-energy");
    write_envmap(dir, 16, 9, patterned_map(16, 9));
    const std::string lights =
        directional(Vec3(0.3f, 0.2f, -0.9f), 1.0) +
        "<emitter type=\"envmap\"><string name=\"filename\" value=\"env.exr\"/><float "
        "name=\"scale\" value=\"0.2\"/></emitter>";
    const std::string shapes = ground(0.5) +
                               "<shape type=\"sphere\"><float name=\"radius\" value=\"0.4\"/>"
                               "<transform name=\"to_world\"><translate z=\"0.5\"/></transform>"
                               "<bsdf type=\"diffuse\"/></shape>";
    const std::string film_extra =
        "<float name=\"start\" value=\"0\"/><float name=\"bin_width\" "
        "value=\"0.5\"/><integer name=\"bins\" value=\"200\"/>";
    const std::string depth = "<integer name=\"max_depth\" value=\"5\"/>";
    auto steady = femto::load_scene_string(
        scene(integrator("transient_path", depth) + ortho_camera(8, 16) + shapes + lights), {},
        dir.string());
    auto transient = femto::load_scene_string(
        scene(integrator("transient_path", depth) + ortho_camera(8, 16, "transient", film_extra) +
              shapes + lights),
        {}, dir.string());
    const std::vector<float> a = femto::testing::render_steady(*steady, 9);
    const std::vector<float> b = femto::testing::render_steady(*transient, 9);
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(b[i], a[i], 1e-5 * (1 + a[i])) << i;
}

// ---- Mitsuba files --------------------------------------------------------------------------

// The three emitters as Mitsuba 0.6 and 3 files write them render the same image as femto's
// own spelling (the 0.6 file in camelCase, a spectrum for the constant's radiance).
TEST(DistantLight, MitsubaFilesLoadUnchanged) {
    const auto dir = femto::testing::temp_dir("envmap-mitsuba");
    write_envmap(dir, 16, 9, patterned_map(16, 9));
    const std::string body = ortho_camera(8, 4) + ground(0.5);
    const std::string native =
        scene(integrator("path", "<integer name=\"max_depth\" value=\"3\"/>") + body +
              "<emitter type=\"envmap\"><string name=\"filename\" value=\"env.exr\"/><float "
              "name=\"scale\" value=\"0.5\"/><transform name=\"to_world\"><rotate x=\"1\" "
              "angle=\"90\"/></transform></emitter><emitter type=\"directional\"><vector "
              "name=\"direction\" x=\"0\" y=\"0.6\" z=\"-0.8\"/><rgb name=\"irradiance\" "
              "value=\"2\"/></emitter><emitter type=\"constant\"><rgb name=\"radiance\" "
              "value=\"0.24096, 0.18966, 0.18178\"/></emitter>");
    const std::string v06 =
        "<scene version=\"0.6.0\">" +
        integrator("path", "<integer name=\"maxDepth\" value=\"3\"/>") + body +
        "<emitter type=\"envmap\"><string name=\"filename\" value=\"env.exr\"/><float "
        "name=\"scale\" value=\"0.5\"/><boolean name=\"cache\" value=\"false\"/><float "
        "name=\"gamma\" value=\"2.2\"/><transform "
        "name=\"toWorld\"><rotate x=\"1\" angle=\"90\"/></transform></emitter><emitter "
        "type=\"directional\"><vector name=\"direction\" x=\"0\" y=\"0.6\" z=\"-0.8\"/><rgb "
        "name=\"irradiance\" value=\"2\"/></emitter><emitter type=\"constant\"><spectrum "
        "name=\"radiance\" value=\"0.2\"/></emitter></scene>";
    auto a = femto::load_scene_string(native, {}, dir.string());
    auto b = femto::load_scene_string(v06, {}, dir.string());
    const std::vector<float> ia = femto::testing::render_steady(*a, 4);
    const std::vector<float> ib = femto::testing::render_steady(*b, 4);
    ASSERT_EQ(ia.size(), ib.size());
    // Mitsuba makes a constant emission spectrum the colour of an equal-energy spectrum
    // (docs/compatibility.md, Spectra): the 0.6 sky is (1.2048, 0.9483, 0.9089) x 0.2, as the
    // native file writes it (to the 4 digits given there).
    for (size_t i = 0; i < ia.size(); ++i) EXPECT_NEAR(ib[i], ia[i], 2e-4 * (1 + ia[i])) << i;
}

// ---- bad input -----------------------------------------------------------------------------

TEST(DistantLight, BadInputIsALocatedError) {
    const auto dir = femto::testing::temp_dir("envmap-bad");
    write_envmap(dir, 1, 1, {1.f, 1.f, 1.f}, "tiny.exr");
    std::vector<float> nan_map(4 * 3 * 3, 1.f);
    nan_map[7] = NAN;
    write_envmap(dir, 4, 3, nan_map, "nan.exr");
    write_envmap(dir, 4, 3, std::vector<float>(36, 1.f), "ok.exr");
    const auto error = [&](const std::string& emitter, const std::string& integ = "path") {
        return load_error(scene(integrator(integ) + ortho_camera(4, 1) + ground(0.5) + emitter), {},
                          dir.string());
    };
    const auto envmap = [](const std::string& file) {
        return "<emitter type=\"envmap\"><string name=\"filename\" value=\"" + file +
               "\"/></emitter>";
    };
    EXPECT_NE(error(envmap("missing.exr")).find("missing.exr"), std::string::npos);
    EXPECT_NE(error(envmap("tiny.exr")).find("at least 2x3"), std::string::npos);
    EXPECT_NE(error(envmap("nan.exr")).find("non-finite value at pixel (2, 0)"), std::string::npos);
    EXPECT_NE(error("<emitter type=\"envmap\"><string name=\"filename\" value=\"ok.exr\"/><float "
                    "name=\"scale\" value=\"-1\"/></emitter>")
                  .find("scale"),
              std::string::npos);
    EXPECT_NE(error("<emitter type=\"directional\"><vector name=\"direction\" x=\"0\" y=\"0\" "
                    "z=\"0\"/></emitter>")
                  .find("non-zero"),
              std::string::npos);
    EXPECT_NE(error("<emitter type=\"directional\"><vector name=\"direction\" x=\"0\" y=\"0\" "
                    "z=\"-1\"/><transform name=\"to_world\"><rotate x=\"1\" angle=\"10\"/>"
                    "</transform></emitter>")
                  .find("not both"),
              std::string::npos);
    EXPECT_NE(error("<emitter type=\"constant\"><rgb name=\"radiance\" value=\"-1\"/></emitter>")
                  .find("negative"),
              std::string::npos);
}

}  // namespace
