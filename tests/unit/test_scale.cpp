// A scene renders the same at every size (issue 19, docs/precision.md): rays leaving a surface
// start off it by an amount that follows the scene's own floating-point error, and time is
// measured between the actual vertices. The conformance matrix checks exact arrival times at
// scales 1e-6 ... 1e6 (TimeOfFlightIsExactAtEveryScale); these tests check the offsets
// themselves and whole scenes (the Cornell box, glass and mirror spheres, fog around a light,
// a glass slab) against scale 1, with films that refuse no contribution at any scale.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "femto/host.h"
#include "femto/scene.h"
#include "femto/shape.h"
#include "femto/testing/render.h"
#include "scene_util.h"

namespace {

using namespace femto;
using femto::testing::Cube;
using femto::testing::MeanAndError;
using femto::testing::render_cube;

using femto::test::xml_number;

// ---- rays leaving a surface -----------------------------------------------------------------

struct SpawnCounts {
    int hits = 0;           // rays that found the shape from outside
    int self_hits = 0;      // spawned rays that hit the surface they left
    int missed_inside = 0;  // inward rays that found nothing (a closed shape must stop them)
    int on_edges = 0;       // hits within rounding of another face's plane (see below)
};

// Whether `hit` lies within 4 p_error of the plane of a triangle of `mesh` that is not
// coplanar with its own: on an edge, within rounding. An inward ray from there may leave
// through the neighbouring face at once, at a distance no float test resolves, so such hits
// are left out of the inward check (they are counted, and must stay rare).
bool on_an_edge(const TriangleMesh& mesh, const Hit& hit) {
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
        const Vec3 p0 = mesh.positions[mesh.indices[3 * t]];
        const Vec3 n = normalize(cross(mesh.positions[mesh.indices[3 * t + 1]] - p0,
                                       mesh.positions[mesh.indices[3 * t + 2]] - p0));
        if (std::abs(dot(n, hit.ng)) < 0.999f && std::abs(dot(n, hit.p - p0)) < 4 * hit.p_error)
            return true;
    }
    return false;
}

// Shoots `n` rays at `shape_xml` (a closed convex shape of size ~`size` centred at `center`)
// and, from each hit, one ray outward and one inward in random directions. Outward rays must
// find nothing; inward rays must hit the shape again, but not the face they left (a coplanar
// triangle) and, on a sphere, not before half the exact chord 2 r |cos|.
SpawnCounts spawn_from(const std::string& shape_xml, const Vec3& center, float size, bool sphere,
                       int n) {
    auto scene = load_scene_string(test::scene_xml(shape_xml));
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    auto unit = [&] {
        const float z = 2 * u(rng) - 1, phi = 2 * kPi * u(rng), r = std::sqrt(1 - z * z);
        return Vec3(r * std::cos(phi), r * std::sin(phi), z);
    };
    SpawnCounts counts;
    for (int i = 0; i < n; ++i) {
        const Vec3 from = center + unit() * (3 * size);
        const Vec3 aim = center + unit() * (0.5f * size * u(rng));
        Hit hit;
        if (!scene->intersect(Ray{from, normalize(aim - from), 0.f, kInfinity}, hit)) continue;
        ++counts.hits;
        Vec3 out = unit();
        if (dot(out, hit.ng) < 0) out = -out;
        Hit again;
        if (scene->intersect(hit.spawn(out), again)) ++counts.self_hits;
        const Vec3 in = -out;
        if (!sphere && on_an_edge(scene->shapes()[0]->mesh(), hit)) {
            ++counts.on_edges;
            continue;
        }
        if (!scene->intersect(hit.spawn(in), again)) {
            ++counts.missed_inside;
        } else if (sphere) {
            const double chord = 2.0 * size * std::abs(dot(in, hit.ng));
            if (distance_between(hit.p, again.p) < 0.5 * chord) ++counts.self_hits;
        } else if (dot(again.ng, hit.ng) > 0.999f) {
            ++counts.self_hits;
        }
    }
    return counts;
}

TEST(Scale, RaysLeavingASurfaceNeverHitItAgain) {
    // Sizes 1e-6 ... 1e6, each at the origin and (up to 1e5) 1e3 sizes away from it, where
    // the shape's coordinates carry 1e3 times more rounding than its size suggests.
    const int n = 4000;
    for (int k = -6; k <= 6; k += 3)
        for (const double away : {0.0, 1e3}) {
            const double s = std::pow(10.0, k);
            if (away * s > 1e8) continue;  // coordinates stay within +-1e9
            const Vec3 c(float(away * s), float(-0.5 * away * s), float(0.25 * away * s));
            SCOPED_TRACE("size 1e" + std::to_string(k) + ", centre " + xml_number(away) +
                         " sizes away");
            const std::string at = "<translate x=\"" + xml_number(c.x) + "\" y=\"" +
                                   xml_number(c.y) + "\" z=\"" + xml_number(c.z) + "\"/>";
            const SpawnCounts sphere = spawn_from(
                "<shape type=\"sphere\"><point name=\"center\" x=\"" + xml_number(c.x) + "\" y=\"" +
                    xml_number(c.y) + "\" z=\"" + xml_number(c.z) +
                    "\"/><float name=\"radius\" value=\"" + xml_number(s) + "\"/></shape>",
                c, float(s), true, n);
            const SpawnCounts cube =
                spawn_from("<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"" +
                               xml_number(s) + "\"/><rotate x=\"1\" y=\"1\" angle=\"30\"/>" + at +
                               "</transform></shape>",
                           c, float(s), false, n);
            for (const SpawnCounts& counts : {sphere, cube}) {
                SCOPED_TRACE(&counts == &sphere ? "sphere" : "cube");
                EXPECT_GT(counts.hits, n / 20);
                EXPECT_EQ(counts.self_hits, 0);
                EXPECT_EQ(counts.missed_inside, 0);
                // The band is 4 p_error wide along the 4 edges of a face 2 sizes wide: 3 % of
                // the hits 1e3 sizes from the origin, 0.003 % at it.
                EXPECT_LE(counts.on_edges, counts.hits / 10);
            }
        }
}

// ---- whole scenes at every scale ------------------------------------------------------------

// What a render at scale s says, in units of scale 1: the light it records (summed over
// pixels, bins and channels) and its mean camera time / s.
struct SceneSummary {
    double energy = 0, mean_time = 0;
};

SceneSummary summarize(const Cube& cube, double start, double width) {
    SceneSummary out;
    double weighted = 0;
    for (int y = 0; y < cube.H; ++y)
        for (int x = 0; x < cube.W; ++x)
            for (int t = 0; t < cube.T; ++t) {
                const double e = cube.energy(y, x, t);
                out.energy += e;
                weighted += e * (start + (t + 0.5) * width);
            }
    out.mean_time = out.energy > 0 ? weighted / out.energy : 0;
    return out;
}

// Renders `scene_at(s)` (a scene whose every length is s times its scale-1 length; the film
// records [start, start + bins * width) times s) with seeds 1..4 at s = 1 and at each scale
// 1e-6, 1e-4, ..., 1e6, and requires the energy and the mean time to agree with scale 1's
// within 4 standard errors of scale 1's estimate (from the spread across the seeds). Same
// seeds at every scale: the renders differ only where float rounding takes a path elsewhere.
template <typename SceneAt>
void expect_scale_free(SceneAt scene_at, double start, double width) {
    const int seeds = 4;
    auto estimate = [&](double s) {
        std::vector<double> energy, time;
        for (int seed = 1; seed <= seeds; ++seed) {
            auto scene = load_scene_string(scene_at(s));
            const SceneSummary m =
                summarize(render_cube(*scene, uint64_t(seed), "scale"), start * s, width * s);
            EXPECT_EQ(scene->sensor().film().rejected().total(), 0u);  // no NaN, Inf, negative
            energy.push_back(m.energy);
            time.push_back(m.mean_time / s);
        }
        return std::make_pair(femto::testing::mean_and_error(energy),
                              femto::testing::mean_and_error(time));
    };
    const auto [e1, t1] = estimate(1.0);
    ASSERT_GT(e1.mean, 0);
    for (int k = -6; k <= 6; k += 2) {
        if (k == 0) continue;
        SCOPED_TRACE("scale 1e" + std::to_string(k));
        const auto [e, t] = estimate(std::pow(10.0, k));
        EXPECT_NEAR(e.mean, e1.mean, 4 * e1.standard_error + 1e-6 * e1.mean);
        EXPECT_NEAR(t.mean, t1.mean, 4 * t1.standard_error + 1e-6 * t1.mean);
    }
}

// The scene's film: 16 x 16 pixels, `bins` bins of `width` from `start`, all times s.
std::string film(double s, double start, double width, int bins) {
    return "<film type=\"transient\"><integer name=\"width\" value=\"16\"/><integer "
           "name=\"height\" value=\"16\"/><float name=\"start\" value=\"" +
           xml_number(start * s) + "\"/><float name=\"bin_width\" value=\"" +
           xml_number(width * s) + "\"/><integer name=\"bins\" value=\"" + std::to_string(bins) +
           "\"/><rfilter type=\"box\"/></film>";
}

std::string camera(double s, const std::string& lookat, double fov, const std::string& film_xml) {
    return "<integrator type=\"transient_path\"><integer name=\"max_depth\" value=\"8\"/>"
           "</integrator><sensor type=\"perspective\"><float name=\"fov\" value=\"" +
           xml_number(fov) + "\"/><transform name=\"to_world\">" + lookat + "<scale value=\"" +
           xml_number(s) +
           "\"/></transform><sampler type=\"independent\"><integer name=\"sample_count\" "
           "value=\"16\"/></sampler>" +
           film_xml + "</sensor>";
}

// A shape whose to_world is `ops` followed by the scale s.
std::string shape(double s, const std::string& type, const std::string& ops,
                  const std::string& inner) {
    return "<shape type=\"" + type + "\"><transform name=\"to_world\">" + ops + "<scale value=\"" +
           xml_number(s) + "\"/></transform>" + inner + "</shape>";
}

TEST(Scale, CornellBoxIsTheSameAtEveryScale) {
    // scenes/cornell-box: the room [-1, 1]^3, a small area light under the ceiling, two boxes.
    auto scene_at = [](double s) {
        const std::string white =
            "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" "
            "value=\"0.725, 0.71, 0.68\"/></bsdf>";
        return "<scene version=\"3.0.0\">" +
               camera(s, "<lookat origin=\"0, 0, 3.9\" target=\"0, 0, 0\" up=\"0, 1, 0\"/>",
                      39.3077, film(s, 3.5, 0.2, 64)) +
               shape(s, "rectangle",
                     "<scale value=\"0.23\"/><rotate x=\"1\" angle=\"90\"/>"
                     "<translate y=\"0.99\"/>",
                     white +
                         "<emitter type=\"area\"><rgb name=\"radiance\" value=\"17, 12, "
                         "4\"/></emitter>") +
               shape(s, "rectangle", "<rotate x=\"1\" angle=\"-90\"/><translate y=\"-1\"/>",
                     white) +
               shape(s, "rectangle", "<rotate x=\"1\" angle=\"90\"/><translate y=\"1\"/>", white) +
               shape(s, "rectangle", "<translate z=\"-1\"/>", white) +
               shape(s, "rectangle", "<rotate y=\"1\" angle=\"90\"/><translate x=\"-1\"/>",
                     "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.63, 0.065, "
                     "0.05\"/></bsdf>") +
               shape(s, "rectangle", "<rotate y=\"1\" angle=\"-90\"/><translate x=\"1\"/>",
                     "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.14, 0.45, "
                     "0.091\"/></bsdf>") +
               shape(s, "cube",
                     "<scale value=\"0.3\"/><rotate y=\"1\" angle=\"-18\"/><translate "
                     "x=\"0.33\" y=\"-0.7\" z=\"0.3\"/>",
                     white) +
               shape(s, "cube",
                     "<scale x=\"0.3\" y=\"0.6\" z=\"0.3\"/><rotate y=\"1\" "
                     "angle=\"15\"/><translate x=\"-0.33\" y=\"-0.4\" z=\"-0.28\"/>",
                     white) +
               "</scene>";
    };
    expect_scale_free(scene_at, 3.5, 0.2);
}

TEST(Scale, GlassAndMirrorSpheresAreTheSameAtEveryScale) {
    // scenes/spheres: a mirror and a glass sphere on a floor before a wall, a spherical light.
    auto scene_at = [](double s) {
        auto sphere = [&](const std::string& centre, double r, const std::string& inner) {
            return shape(
                s, "sphere",
                "<scale value=\"" + xml_number(r) + "\"/><translate value=\"" + centre + "\"/>",
                inner);
        };
        return "<scene version=\"3.0.0\">" +
               camera(s, "<lookat origin=\"0, 1.3, 3.8\" target=\"0, 0.4, 0\" up=\"0, 1, 0\"/>", 45,
                      film(s, 4.5, 0.25, 32)) +
               shape(s, "rectangle", "<scale value=\"3\"/><rotate x=\"1\" angle=\"-90\"/>",
                     "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.7, 0.7, "
                     "0.7\"/></bsdf>") +
               shape(s, "rectangle", "<scale x=\"3\" y=\"1.5\"/><translate y=\"1.5\" z=\"-1.5\"/>",
                     "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.6, 0.45, "
                     "0.3\"/></bsdf>") +
               sphere("-0.65, 0.5, 0", 0.5, "<bsdf type=\"conductor\"/>") +
               sphere("0.65, 0.5, 0", 0.5,
                      "<bsdf type=\"dielectric\"><float name=\"int_ior\" value=\"1.5168\"/>"
                      "</bsdf>") +
               sphere("1.2, 2.6, 1.6", 0.3,
                      "<emitter type=\"area\"><rgb name=\"radiance\" value=\"25, 25, "
                      "25\"/></emitter>") +
               "</scene>";
    };
    expect_scale_free(scene_at, 4.5, 0.25);
}

TEST(Scale, FogPointIsTheSameAtEveryScale) {
    // scenes/fog-point: a ball of radius 2 of fog (sigma_t 4.1 / s: the same optical depths at
    // every scale, albedo 0.98) around a small bright bead, seen from 10 away.
    auto scene_at = [](double s) {
        return "<scene version=\"3.0.0\"><medium type=\"homogeneous\" id=\"fog\"><float "
               "name=\"sigma_t\" value=\"" +
               xml_number(4.1 / s) + "\"/><float name=\"albedo\" value=\"0.98\"/></medium>" +
               camera(s, "<lookat origin=\"0, 0, 10\" target=\"0, 0, 0\" up=\"0, 1, 0\"/>", 26,
                      film(s, 8, 0.5, 24)) +
               shape(s, "sphere", "<scale value=\"2\"/>",
                     "<bsdf type=\"null\"/><ref name=\"interior\" id=\"fog\"/>") +
               shape(s, "sphere", "<scale value=\"0.25\"/>",
                     "<bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"0\"/></bsdf>"
                     "<emitter type=\"area\"><rgb name=\"radiance\" value=\"100\"/></emitter>") +
               "</scene>";
    };
    expect_scale_free(scene_at, 8, 0.5);
}

TEST(Scale, GlassSlabIsTheSameAtEveryScale) {
    // A glass slab (index 1.5, 0.4 thick) between the camera and a light panel: the refraction
    // delay and the light through it must not depend on the scene's size.
    auto scene_at = [](double s) {
        return "<scene version=\"3.0.0\">" +
               camera(s, "<lookat origin=\"0, 0, 4\" target=\"0, 0, 0\" up=\"0, 1, 0\"/>", 30,
                      film(s, 5, 0.1, 40)) +
               shape(s, "cube", "<scale x=\"2\" y=\"2\" z=\"0.2\"/>",
                     "<bsdf type=\"dielectric\"><float name=\"int_ior\" value=\"1.5\"/></bsdf>") +
               shape(s, "rectangle", "<scale value=\"1.5\"/><translate z=\"-1.5\"/>",
                     "<emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter>") +
               "</scene>";
    };
    expect_scale_free(scene_at, 5, 0.1);
}

}  // namespace
