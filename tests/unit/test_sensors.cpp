// Measurement sensors (issue 12 §2): radiancemeter, irradiancemeter and spherical, each against
// a closed form with steady and transient films.
//  - spherical: the film position -> direction map against its density (chi-square); inside a
//    uniformly emitting sphere every pixel holds the sphere's radiance, arriving at its radius;
//    the ballistic term of a point light in an absorbing medium, splatted by the light tracer,
//    gives the fluence I exp(-sigma_t d) / d^2 at time d;
//  - irradiancemeter: inside an emitting sphere it reads pi L (path tracer and BDPT, exactly;
//    the light tracer within its error); under a point light a disk reads
//    (2 I / a^2)(1 - h / sqrt(a^2 + h^2)) and its time profile (2 I h / a^2)(1/t0 - 1/t1) per
//    bin, within errors derived from the estimator's own variance;
//  - radiancemeter: the radiance of a Lambertian plane under a point light, at its time;
//  - bad input (wrong film sizes, a meter without its shape or with a transform, a camera in a
//    shape, two sensors, a scaled spherical camera, light tracing onto a single ray) is a
//    located error.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "chi2.h"
#include "cube_util.h"
#include "femto/host.h"
#include "femto/scene.h"
#include "femto/sensor.h"
#include "scene_util.h"

using namespace femto;
using namespace femto::test;
using femto_test::Chi2Options;
using femto_test::Chi2Result;

namespace {

constexpr double kPiD = 3.14159265358979323846;

std::string film_1x1(const std::string& type, const std::string& extra = "") {
    return "<film type=\"" + type +
           "\"><integer name=\"width\" value=\"1\"/><integer name=\"height\" value=\"1\"/>" +
           extra + "</film>";
}

// A black sphere of radius 2 around `centre`, its inside emitting radiance 0.7.
std::string emitting_sphere(const std::string& centre, const std::string& inside = "") {
    return "<shape type=\"sphere\"><point name=\"center\" value=\"" + centre +
           "\"/><float name=\"radius\" value=\"2\"/><boolean name=\"flip_normals\" "
           "value=\"true\"/><bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"0\"/></bsdf>"
           "<emitter type=\"area\"><rgb name=\"radiance\" value=\"0.7\"/></emitter></shape>" +
           inside;
}

std::string scene(const std::string& integrator, const std::string& body) {
    return "<scene version=\"3.0.0\"><integrator type=\"" + integrator +
           "\"><integer name=\"max_depth\" value=\"6\"/></integrator>" + body + "</scene>";
}

// Sum of the cube's bins of pixel (0, 0), channel 0.
double cube_total(const Cube& cube) {
    double sum = 0;
    for (int t = 0; t < cube.T; ++t) sum += cube.at(0, 0, t, 0);
    return sum;
}

}  // namespace

// ---- spherical -------------------------------------------------------------------------------

// Film positions drawn uniformly leave in directions of density pdf_direction(): checked in
// world (theta, phi), where the density is pdf_direction(d) sin(theta), for a rotated camera.
TEST(SphericalSensor, DirectionsFollowTheirDensity) {
    auto sc = load_scene_string(
        scene("path",
              "<sensor type=\"spherical\"><transform name=\"to_world\"><lookat origin=\"1,2,3\" "
              "target=\"2,2.5,3\" up=\"0,0,1\"/></transform><film type=\"hdrfilm\"><integer "
              "name=\"width\" value=\"64\"/><integer name=\"height\" value=\"32\"/></film>"
              "</sensor>" +
                  std::string(kRect)));
    const Sensor& sensor = sc->sensor();
    Chi2Options o;
    o.nx = 64, o.ny = 128, o.x0 = 0, o.x1 = kPiD, o.y0 = 0, o.y1 = 2 * kPiD;
    o.samples = 2000000;
    o.seed = femto_test::seed_from_name("SphericalSensor.DirectionsFollowTheirDensity");
    auto direction = [](double theta, double phi) {
        return Vec3(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                    float(std::cos(theta)));
    };
    const Chi2Result r = femto_test::chi2_test(
        o,
        [&](Pcg32& rng) -> std::optional<std::pair<double, double>> {
            const float x = rng.next_float() * 64, y = rng.next_float() * 32;
            const Vec3 d = sensor.sample_ray({x, y}, {0.5f, 0.5f}).d;
            double phi = std::atan2(double(d.y), double(d.x));
            if (phi < 0) phi += 2 * kPiD;
            return std::make_pair(std::acos(std::clamp(double(d.z), -1.0, 1.0)), phi);
        },
        [&](double theta, double phi) {
            return double(sensor.pdf_direction(direction(theta, phi))) * std::sin(theta);
        });
    EXPECT_TRUE(r.error.empty()) << r.describe();
    EXPECT_GT(r.p_value, 0.01) << r.describe();
    EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3) << r.describe();
}

// Mitsuba 0.6's layout: the top row looks along local +y, the centre column along +z, the left
// edge along -z; a connection from a point lands where the camera ray toward it starts.
TEST(SphericalSensor, FilmLayoutAndConnectionsAgree) {
    auto sc = load_scene_string(
        scene("path",
              "<sensor type=\"spherical\"><transform name=\"to_world\"><translate x=\"1\" "
              "y=\"2\" z=\"3\"/></transform><film type=\"hdrfilm\"><integer name=\"width\" "
              "value=\"40\"/><integer name=\"height\" value=\"20\"/></film></sensor>" +
                  std::string(kRect)));
    const Sensor& s = sc->sensor();
    auto near = [](const Vec3& a, const Vec3& b) { return length(a - b) < 1e-5f; };
    EXPECT_TRUE(near(s.sample_ray({20, 10}, {}).d, {0, 0, 1}));
    EXPECT_TRUE(near(s.sample_ray({0, 10}, {}).d, {0, 0, -1}));
    EXPECT_TRUE(near(s.sample_ray({10, 10}, {}).d, {1, 0, 0}));
    EXPECT_TRUE(near(s.sample_ray({20, 0}, {}).d, {0, 1, 0}));
    EXPECT_TRUE(near(s.sample_ray({3, 3}, {}).o, {1, 2, 3}));
    Pcg32 rng(7, 1);
    for (int i = 0; i < 1000; ++i) {
        const Vec2 pos{rng.next_float() * 40, rng.next_float() * 20};
        const Ray ray = s.sample_ray(pos, {});
        const SensorSample c = s.sample_direct(ray.o + ray.d * 3.f, {});
        ASSERT_TRUE(c.valid());
        EXPECT_NEAR(c.pos.x, pos.x, 1e-3f);
        EXPECT_NEAR(c.pos.y, pos.y, 1e-3f);
        EXPECT_NEAR(c.distance, 3.0, 1e-5);
        EXPECT_NEAR(c.weight, s.pdf_direction(-c.wi) / float(c.distance * c.distance),
                    1e-5f * c.weight);
    }
}

// Inside a black sphere of radius 2 whose inside emits 0.7, every direction sees 0.7, all of it
// arriving at time 2. The path tracer's estimate is exact (no noise), so the comparison is to
// float precision. BDPT adds light paths splatted onto the camera (the sphere's points seen
// from it): every pixel's mean is still 0.7, checked on the image's mean against the pixels'
// spread, and nothing arrives outside the bin of time 2.
TEST(SphericalSensor, InsideAnEmittingSphereEveryPixelSeesItsRadianceAtItsRadius) {
    for (const char* integrator : {"path", "transient_bdpt"}) {
        SCOPED_TRACE(integrator);
        const bool exact = std::string(integrator) == "path";
        auto sc = load_scene_string(scene(
            integrator,
            "<sensor type=\"spherical\"><transform name=\"to_world\"><translate "
            "x=\"1\" y=\"2\" z=\"3\"/></transform>" +
                independent_sampler(exact ? 2 : 64) + box_transient_film(16, 8, 1.905, 0.01, 20) +
                "</sensor>" + emitting_sphere("1,2,3")));
        const Cube cube = render_cube(*sc, 1, "spherical-inside");
        std::vector<double> pixels;
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 16; ++x)
                for (int t = 0; t < cube.T; ++t) {
                    if (t == 9) {
                        pixels.push_back(cube.at(y, x, t, 0));
                        if (exact) {
                            ASSERT_NEAR(cube.at(y, x, t, 0), 0.7f, 1e-5f);
                        }
                    } else {
                        ASSERT_EQ(cube.at(y, x, t, 0), 0.f) << "pixel " << x << ", " << y;
                    }
                }
        const auto [mean, error] = femto::testing::mean_and_error(pixels);
        EXPECT_NEAR(mean, 0.7, exact ? 1e-5 : 5 * error) << "+- " << error;
    }
}

// A point light of intensity 5, 3 units from the camera, in a purely absorbing medium
// (sigma_t 0.4): the only light is ballistic, fluence I exp(-sigma_t d) / d^2, arriving at
// time d. The light tracer's connection from the light is deterministic, so the pixel it lands
// in holds fluence x pixels x pdf_direction exactly.
TEST(SphericalSensor, BallisticTermOfAPointLightInAMediumIsExact) {
    const std::string medium =
        "<medium type=\"homogeneous\" id=\"ink\"><float name=\"sigma_t\" value=\"0.4\"/><float "
        "name=\"albedo\" value=\"0\"/></medium>";
    const std::string body =
        medium + "<sensor type=\"spherical\"><ref id=\"ink\"/>" + independent_sampler(4) +
        box_transient_film(32, 16, 2.955, 0.01, 10) +
        "</sensor><emitter type=\"point\"><point name=\"position\" value=\"1,2,-2\"/>"
        "<float name=\"intensity\" value=\"5\"/><ref id=\"ink\"/></emitter>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><translate z=\"-50\"/></transform>"
        "<bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"0\"/></bsdf></shape>";
    auto sc = load_scene_string(scene("transient_light", body));
    const Cube cube = render_cube(*sc, 3, "spherical-ballistic");
    const Vec3 to_light = normalize(Vec3(1, 2, -2));  // distance 3
    const SensorSample c = sc->sensor().sample_direct({1, 2, -2}, {});
    ASSERT_TRUE(c.valid());
    const int px = int(c.pos.x), py = int(c.pos.y);
    const double fluence = 5 * std::exp(-0.4 * 3) / 9;
    const double expected = fluence * 32 * 16 * sc->sensor().pdf_direction(to_light);
    double elsewhere = 0;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 32; ++x)
            for (int t = 0; t < cube.T; ++t)
                if (x != px || y != py || t != 4) elsewhere += std::abs(cube.at(y, x, t, 0));
    EXPECT_NEAR(cube.at(py, px, 4, 0), expected, 1e-4 * expected);
    EXPECT_EQ(elsewhere, 0.0);
}

// ---- irradiancemeter -------------------------------------------------------------------------

// A disk of radius 0.5 at the centre of the emitting sphere: every cosine-distributed ray from
// its front sees 0.7, so the irradiance is pi x 0.7 exactly for the camera-side integrators
// (BDPT leaves out its connections to a sensor with area; with them its weights would not sum
// to one here). The light tracer estimates it from the sphere's emission; its error comes from
// eight independent renders.
TEST(IrradianceMeter, InsideAnEmittingSphereReadsPiL) {
    const std::string meter =
        "<shape type=\"disk\"><transform name=\"to_world\"><scale value=\"0.5\"/><translate "
        "x=\"1\" y=\"2\" z=\"3\"/></transform><bsdf type=\"diffuse\"><float name=\"reflectance\" "
        "value=\"0\"/></bsdf><sensor type=\"irradiancemeter\">" +
        independent_sampler(4096) + film_1x1("hdrfilm", "<rfilter type=\"box\"/>") +
        "</sensor></shape>";
    for (const char* integrator : {"path", "transient_bdpt"}) {
        SCOPED_TRACE(integrator);
        auto sc = load_scene_string(scene(integrator, meter + emitting_sphere("1,2,3")));
        const std::vector<float> rgb = femto::testing::render_steady(*sc, 1);
        EXPECT_NEAR(rgb[0], kPiD * 0.7, 1e-5);
    }
    std::vector<double> light;
    for (uint64_t seed = 1; seed <= 8; ++seed) {
        auto sc = load_scene_string(scene("transient_light", meter + emitting_sphere("1,2,3")));
        light.push_back(femto::testing::render_steady(*sc, seed)[0]);
    }
    const auto [mean, error] = femto::testing::mean_and_error(light);
    EXPECT_GT(error, 0);
    EXPECT_NEAR(mean, kPiD * 0.7, 5 * error) << "+- " << error;
}

// A disk of radius a = 1 facing a point light of intensity I = 5 at height h = 2. Light tracing
// samples a uniform point of the disk per light path; its splat I h / t^3 (t = distance to the
// light, the arrival time) has mean E = (2 I / a^2)(1 - h / sqrt(a^2 + h^2)) and second moment
// (I^2 h^2 / a^2)(1 / (2 h^4) - 1 / (2 (a^2 + h^2)^2)); per time bin [t0, t1) the mean is
// (2 I h / a^2)(1/t0 - 1/t1) and the second moment (I^2 h^2 / a^2)(1/(2 t0^4) - 1/(2 t1^4)).
TEST(IrradianceMeter, PointLightOverADiskMatchesTheClosedForm) {
    const double I = 5, h = 2, a = 1, start = 1.98, width = 0.02;
    const int bins = 14, spp = 20000;
    const std::string body =
        "<shape type=\"disk\"><sensor type=\"irradiancemeter\">" + independent_sampler(spp) +
        box_transient_film(1, 1, start, width, bins) +
        "</sensor></shape><emitter type=\"point\"><point name=\"position\" value=\"0,0,2\"/>"
        "<float name=\"intensity\" value=\"5\"/></emitter>";
    auto sc = load_scene_string(scene("transient_light", body));
    const Cube cube = render_cube(*sc, 11, "irradiance-disk");
    const double E = 2 * I / (a * a) * (1 - h / std::sqrt(a * a + h * h));
    const double second =
        I * I * h * h / (a * a) * (1 / (2 * std::pow(h, 4)) - 1 / (2 * std::pow(a * a + h * h, 2)));
    const double sigma = std::sqrt((second - E * E) / spp);
    EXPECT_NEAR(cube_total(cube), E, 5 * sigma) << "sigma " << sigma;
    const double t_max = std::sqrt(a * a + h * h);
    double chi2 = 0;
    int dof = 0;
    for (int b = 0; b < bins; ++b) {
        const double t0 = std::max(h, start + b * width),
                     t1 = std::min(t_max, start + (b + 1) * width);
        if (!(t1 > t0)) {
            EXPECT_EQ(cube.at(0, 0, b, 0), 0.f) << "bin " << b;
            continue;
        }
        const double mean = 2 * I * h / (a * a) * (1 / t0 - 1 / t1);
        const double m2 =
            I * I * h * h / (a * a) * (1 / (2 * std::pow(t0, 4)) - 1 / (2 * std::pow(t1, 4)));
        const double var = (m2 - mean * mean) / spp;
        const double d = cube.at(0, 0, b, 0) - mean;
        chi2 += d * d / var;
        ++dof;
    }
    // The bins' estimates are nearly independent (each path adds to one bin; their covariance
    // is -mean_i mean_j / spp, small against the variances): chi-square with `dof` degrees.
    EXPECT_GT(femto_test::chi2_p_value(chi2, dof), 1e-3) << "chi2 " << chi2 << " dof " << dof;
}

// ---- radiancemeter ---------------------------------------------------------------------------

// Looking straight down at (0.5, 0, 0) of a Lambertian plane (albedo 0.6) from height 3, under
// a point light of intensity 5 at (0, 0, 1.5): L = (0.6 / pi) I cos / r^2 with r^2 = 2.5 and
// cos = 1.5 / sqrt(2.5), arriving at camera time 3 + sqrt(2.5). Every sample is the same ray
// and the same shadow ray, so the value is exact.
TEST(RadianceMeter, LambertianPlaneUnderAPointLight) {
    const double L = 0.6 / kPiD * 5 * (1.5 / std::sqrt(2.5)) / 2.5, t = 3 + std::sqrt(2.5);
    const std::string body =
        "<sensor type=\"radiancemeter\"><point name=\"origin\" value=\"0.5,0,3\"/><vector "
        "name=\"direction\" value=\"0,0,-1\"/>" +
        independent_sampler(16) + box_transient_film(1, 1, t - 0.25, 0.1, 5) +
        "</sensor><shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"10\"/>"
        "</transform><bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"0.6\"/></bsdf>"
        "</shape><emitter type=\"point\"><point name=\"position\" value=\"0,0,1.5\"/><float "
        "name=\"intensity\" value=\"5\"/></emitter>";
    for (const char* integrator : {"path", "transient_bdpt"}) {
        SCOPED_TRACE(integrator);
        auto sc = load_scene_string(scene(integrator, body));
        const Cube cube = render_cube(*sc, 2, "radiancemeter");
        for (int b = 0; b < cube.T; ++b)
            EXPECT_NEAR(cube.at(0, 0, b, 0), b == 2 ? L : 0.0, 1e-5 * L) << "bin " << b;
    }
}

// ---- bad input -------------------------------------------------------------------------------

TEST(MeasurementSensors, BadInputIsALocatedError) {
    const std::string light =
        "<emitter type=\"point\"><point name=\"position\" value=\"0,0,1\"/></emitter>";
    const std::string one = film_1x1("hdrfilm", "<rfilter type=\"box\"/>");
    const std::string two =
        "<film type=\"hdrfilm\"><integer name=\"width\" value=\"2\"/><integer "
        "name=\"height\" value=\"1\"/></film>";
    const std::string meter = "<sensor type=\"irradiancemeter\">";
    const std::string disk = "<shape type=\"disk\">";
    // (scene body, its third line holding the offending element; what the message must say)
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"<sensor type=\"radiancemeter\">" + two + "</sensor>", "must be 1 x 1 pixels, not 2 x 1"},
        {"<sensor type=\"radiancemeter\"><point name=\"origin\" value=\"0,0,1\"/>" + one +
             "</sensor>",
         "give both origin and direction"},
        {"<sensor type=\"radiancemeter\"><vector name=\"direction\" value=\"0,0,0\"/><point "
         "name=\"origin\" value=\"0,0,1\"/>" +
             one + "</sensor>",
         "zero length"},
        {meter + one + "</sensor>", "nest it in the <shape> it measures on"},
        {disk + meter + two + "</sensor></shape>", "must be 1 x 1 pixels"},
        {disk + meter + "<transform name=\"to_world\"><translate x=\"1\"/></transform>" + one +
             "</sensor></shape>",
         "takes its place from the shape"},
        {disk + "<sensor type=\"perspective\"/></shape>", "cannot be nested in a <shape>"},
        {disk + meter + film_1x1("hdrfilm", "<rfilter type=\"gaussian\"/>") + "</sensor></shape>",
         "irradiancemeter needs a box reconstruction filter"},
        {"<sensor type=\"spherical\"><transform name=\"to_world\"><matrix value=\"1 0.5 0 0 0 "
         "0.8660254 0 0 0 0 1 0 0 0 0 1\"/></transform></sensor>",
         "must not scale"},
        {"<sensor type=\"perspective\"/>" + disk + meter + one + "</sensor></shape>",
         "more than one <sensor>"},
        {"<sensor type=\"spherical\"><transform name=\"to_world\"><scale value=\"2\"/>"
         "</transform></sensor>",
         "must not scale"},
    };
    for (const auto& [body, expected] : cases) {
        SCOPED_TRACE(body);
        // The scene's first line holds <scene> and the integrator; the body starts on line 3.
        const std::string message = load_error(scene("path", "\n\n" + body + light));
        EXPECT_NE(message.find(expected), std::string::npos) << message;
        EXPECT_EQ(message.rfind("<string>:3:", 0), 0u) << message;
    }
    // The light tracer cannot reach a single ray.
    auto sc = load_scene_string(scene(
        "transient_light", "<sensor type=\"radiancemeter\">" + one + "</sensor>" + kRect + light));
    try {
        femto::testing::render_steady(*sc, 1);
        ADD_FAILURE() << "transient_light rendered onto a radiancemeter";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("\"radiancemeter\" sensor"), std::string::npos)
            << e.what();
    }
}
