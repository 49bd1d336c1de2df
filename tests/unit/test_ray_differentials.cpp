// Ray differentials and pixel footprints (Ray::differential, Sensor::sample_differential(),
// Hit::footprint), through the scene's own intersection (Embree):
//  - an orthographic camera looking straight down at a scaled rectangle: the footprint in
//    closed form at every hit;
//  - a perspective camera above the same plane: dp at the image centre from the field of view,
//    dd from two sample_ray() calls one pixel apart;
//  - a sphere and a bent mesh with vertex normals: dn (and a sphere's uv change) against the
//    finite difference of the main ray's hit and the offset ray's;
//  - instances: the footprint of an instanced rectangle (and sphere) equals that of the same
//    shape placed directly;
//  - no footprint for secondary rays and for sensors without a film plane.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "femto/host.h"
#include "femto/scene.h"
#include "femto/sensor.h"
#include "femto/shape.h"
#include "scene_util.h"
#include "shape_test_util.h"

namespace {

using namespace femto;
using femto::test::scene_xml;

constexpr double kPiD = 3.14159265358979323846;

std::string film(int w, int h, const std::string& extra = "") {
    return "<film type=\"hdrfilm\"><integer name=\"width\" value=\"" + std::to_string(w) +
           "\"/><integer name=\"height\" value=\"" + std::to_string(h) + "\"/>" + extra + "</film>";
}

// A camera at (0, 0, height) looking down at the origin, +y up on the image.
std::string camera_above(const std::string& type, float height, const std::string& params,
                         const std::string& scale, int w, int h) {
    return "<sensor type=\"" + type + "\">" + params + "<transform name=\"to_world\">" + scale +
           "<lookat origin=\"0,0," + std::to_string(height) +
           "\" target=\"0,0,0\" up=\"0,1,0\"/></transform>" + film(w, h) + "</sensor>";
}

std::string rectangle(float s) {
    return "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"" +
           std::to_string(s) + "\"/></transform></shape>";
}

// The camera ray through film position `pos` (aperture sample 0.5, 0.5) with its differential.
struct CameraRay {
    Ray ray;
    RayDifferential differential;
};
CameraRay camera_ray(const Sensor& sensor, Vec2 pos) {
    CameraRay c;
    c.ray = sensor.sample_ray(pos, {0.5f, 0.5f});
    EXPECT_TRUE(sensor.sample_differential(pos, {0.5f, 0.5f}, c.differential));
    return c;
}

// The first hit of the camera ray through `pos`, with its footprint; false on a miss.
bool footprint_hit(const Scene& scene, Vec2 pos, Hit& hit) {
    CameraRay c = camera_ray(scene.sensor(), pos);
    c.ray.differential = &c.differential;
    return scene.intersect(c.ray, hit);
}

// The hit of the neighbouring ray (x or y), traced without a differential.
bool offset_hit(const Scene& scene, Vec2 pos, bool along_x, Hit& hit) {
    const CameraRay c = camera_ray(scene.sensor(), pos);
    const Ray r{along_x ? c.differential.dx_o : c.differential.dy_o,
                along_x ? c.differential.dx_d : c.differential.dy_d, 0.f, kInfinity};
    return scene.intersect(r, hit);
}

void expect_near(const Vec3& a, const Vec3& b, float tol, const char* what) {
    EXPECT_NEAR(a.x, b.x, tol) << what;
    EXPECT_NEAR(a.y, b.y, tol) << what;
    EXPECT_NEAR(a.z, b.z, tol) << what;
}
void expect_near(Vec2 a, Vec2 b, float tol, const char* what) {
    EXPECT_NEAR(a.x, b.x, tol) << what;
    EXPECT_NEAR(a.y, b.y, tol) << what;
}

// Orthographic camera scaled by e (its view spans 2e across the film's width) looking straight
// down (-z) at a rectangle scaled by s, whose uv = ((x / s + 1) / 2, (y / s + 1) / 2). The
// camera's local +x is the image's left, world -x (Mitsuba's lookat), so a step right on the
// film moves the ray by +2e / W in world x and u grows by that over 2s; film y grows
// downward while world y and v grow upward, so v shrinks by 2e / W / (2s) per step (square
// pixels: the height spans 2e H / W).
TEST(RayDifferentials, OrthographicOverRectangleInClosedForm) {
    constexpr int W = 32, H = 16;
    constexpr float e = 1.5f, s = 2.f;
    const auto scene = load_scene_string(
        scene_xml(camera_above("orthographic", 5.f, "",
                               "<scale value=\"" + std::to_string(e) + "\"/>", W, H) +
                  rectangle(s)));
    const float pixel = 2 * e / W;  // world size of one pixel
    const float du = pixel / (2 * s);
    int hits = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            Hit hit;
            ASSERT_TRUE(footprint_hit(*scene, {x + 0.3f, y + 0.6f}, hit));
            ++hits;
            const PixelFootprint& fp = hit.footprint;
            ASSERT_TRUE(fp.valid);
            expect_near(fp.duv_dx, {du, 0.f}, 1e-5f * du, "duv_dx");
            expect_near(fp.duv_dy, {0.f, -du}, 1e-5f * du, "duv_dy");
            expect_near(fp.dp_dx, {pixel, 0, 0}, 1e-5f * pixel, "dp_dx");
            expect_near(fp.dp_dy, {0, -pixel, 0}, 1e-5f * pixel, "dp_dy");
            expect_near(fp.dn_dx, Vec3(0.f), 0.f, "dn_dx");
            expect_near(fp.dn_dy, Vec3(0.f), 0.f, "dn_dy");
            expect_near(fp.dd_dx, Vec3(0.f), 0.f, "dd_dx");
            expect_near(fp.dd_dy, Vec3(0.f), 0.f, "dd_dy");
        }
    EXPECT_EQ(hits, W * H);
}

// A pinhole at distance d above the plane with a horizontal field of view fov: at the image
// centre one pixel spans 2 d tan(fov / 2) / W on the plane, and the direction changes as two
// sample_ray() calls one pixel apart say.
TEST(RayDifferentials, PerspectiveAtTheImageCentre) {
    constexpr int W = 64, H = 48;
    constexpr float d = 3.f, fov = 50.f;
    const auto scene = load_scene_string(
        scene_xml(camera_above("perspective", d, "<float name=\"fov\" value=\"50\"/>", "", W, H) +
                  rectangle(10.f)));
    const Vec2 centre{W / 2.f, H / 2.f};
    Hit hit;
    ASSERT_TRUE(footprint_hit(*scene, centre, hit));
    const PixelFootprint& fp = hit.footprint;
    ASSERT_TRUE(fp.valid);
    const float pixel = float(2 * d * std::tan(fov / 2 * kPiD / 180) / W);
    EXPECT_NEAR(fp.dp_dx.x, pixel, 1e-4f * pixel);
    EXPECT_NEAR(fp.dp_dx.y, 0.f, 1e-4f * pixel);
    EXPECT_NEAR(fp.dp_dy.y, -pixel, 1e-4f * pixel);  // square pixels; film y points down
    EXPECT_NEAR(fp.dp_dx.z, 0.f, 1e-6f);
    expect_near(fp.dn_dx, Vec3(0.f), 0.f, "flat: dn_dx");
    const Sensor& sensor = scene->sensor();
    for (const Vec2 pos : {centre, Vec2{5.3f, 40.2f}}) {
        Hit h;
        ASSERT_TRUE(footprint_hit(*scene, pos, h));
        const Vec3 d0 = sensor.sample_ray(pos, {0.5f, 0.5f}).d;
        expect_near(h.footprint.dd_dx, sensor.sample_ray({pos.x + 1, pos.y}, {0.5f, 0.5f}).d - d0,
                    1e-6f, "dd_dx");
        expect_near(h.footprint.dd_dy, sensor.sample_ray({pos.x, pos.y + 1}, {0.5f, 0.5f}).d - d0,
                    1e-6f, "dd_dy");
        EXPECT_GT(length(h.footprint.dd_dx), 0.5f * pixel / d);
    }
}

// A sphere seen from the side (away from its poles and its u seam): the normal turns by
// dp / radius, and uv moves as the offset ray's hit says, to first order (the pixel is 1/100
// of the radius).
TEST(RayDifferentials, SphereNormalAndUvChange) {
    constexpr int W = 400, H = 300;
    constexpr float radius = 1.3f;
    const auto scene = load_scene_string(scene_xml(
        "<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/><transform "
        "name=\"to_world\"><lookat origin=\"0.2,-6,0.1\" target=\"0.2,0,0.1\" up=\"0,0,1\"/>"
        "</transform>" +
        film(W, H) +
        "</sensor><shape type=\"sphere\"><point name=\"center\" value=\"0.2,0,0.1\"/><float "
        "name=\"radius\" value=\"1.3\"/></shape>"));
    int checked = 0;
    for (const Vec2 pos :
         {Vec2{200.5f, 150.5f}, Vec2{150.2f, 120.7f}, Vec2{260.8f, 190.1f}, Vec2{230.4f, 100.9f}}) {
        Hit hit, hx, hy;
        ASSERT_TRUE(footprint_hit(*scene, pos, hit));
        ASSERT_TRUE(offset_hit(*scene, pos, true, hx));
        ASSERT_TRUE(offset_hit(*scene, pos, false, hy));
        const PixelFootprint& fp = hit.footprint;
        ASSERT_TRUE(fp.valid);
        const float tol_n = 1e-4f * length(fp.dn_dx);
        expect_near(fp.dn_dx, fp.dp_dx / radius, tol_n, "dn_dx");
        expect_near(fp.dn_dy, fp.dp_dy / radius, tol_n, "dn_dy");
        const Vec2 fd_x = hx.uv - hit.uv, fd_y = hy.uv - hit.uv;
        EXPECT_NEAR(length(Vec3(fp.duv_dx.x, fp.duv_dx.y, 0)), length(Vec3(fd_x.x, fd_x.y, 0)),
                    0.05f * length(Vec3(fd_x.x, fd_x.y, 0)));
        expect_near(fp.duv_dx, fd_x, 0.05f * length(Vec3(fd_x.x, fd_x.y, 0)), "duv_dx");
        expect_near(fp.duv_dy, fd_y, 0.05f * length(Vec3(fd_y.x, fd_y.y, 0)), "duv_dy");
        expect_near(fp.dp_dx, hx.p - hit.p, 0.05f * length(hx.p - hit.p), "dp_dx");
        expect_near(fp.dn_dx, hx.sh.n - hit.sh.n, 0.05f * length(hx.sh.n - hit.sh.n), "fd dn");
        ++checked;
    }
    EXPECT_EQ(checked, 4);
}

// A bent quad (two triangles) with tilted vertex normals: the footprint's dn against the finite
// difference of the shading normals of the main and the offset rays' hits (on one triangle).
TEST(RayDifferentials, MeshVertexNormalsChange) {
    constexpr const char* kBentQuad = R"(v -1 -1 0
v 1 -1 0.2
v 1 1 0.5
v -1 1 0.1
vn -0.4 -0.3 1
vn 0.5 -0.2 1
vn 0.3 0.4 1
vn -0.2 0.5 1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
f 1/1/1 2/2/2 3/3/3
f 1/1/1 3/3/3 4/4/4
)";
    femto_shape_test::ScratchDir dir;
    constexpr int W = 400, H = 400;
    const auto scene = load_scene_string(
        scene_xml(camera_above("perspective", 4.f, "<float name=\"fov\" value=\"35\"/>", "", W, H) +
                  "<shape type=\"obj\"><string name=\"filename\" value=\"" +
                  dir.write("bent.obj", kBentQuad) + "\"/></shape>"));
    int checked = 0;
    for (const Vec2 pos : {Vec2{260.3f, 110.6f}, Vec2{300.1f, 180.2f}, Vec2{120.4f, 280.5f},
                           Vec2{90.7f, 220.3f}, Vec2{150.5f, 150.5f}}) {
        Hit hit, hx, hy;
        ASSERT_TRUE(footprint_hit(*scene, pos, hit));
        ASSERT_TRUE(offset_hit(*scene, pos, true, hx));
        ASSERT_TRUE(offset_hit(*scene, pos, false, hy));
        if (hx.prim != hit.prim || hy.prim != hit.prim) continue;  // across the crease
        const PixelFootprint& fp = hit.footprint;
        ASSERT_TRUE(fp.valid);
        const Vec3 fd_x = hx.sh.n - hit.sh.n, fd_y = hy.sh.n - hit.sh.n;
        ASSERT_GT(length(fd_x), 1e-4f);
        expect_near(fp.dn_dx, fd_x, 0.03f * length(fd_x), "dn_dx");
        expect_near(fp.dn_dy, fd_y, 0.03f * length(fd_y), "dn_dy");
        EXPECT_NEAR(dot(fp.dn_dx, hit.sh.n), 0.f, 1e-6f);  // a unit normal turns, not grows
        expect_near(fp.duv_dx, hx.uv - hit.uv, 0.03f * length(Vec3(fp.duv_dx.x, fp.duv_dx.y, 0)),
                    "duv_dx");
        ++checked;
    }
    EXPECT_GE(checked, 4);
}

void expect_same_footprint(const PixelFootprint& a, const PixelFootprint& b, bool with_uv) {
    ASSERT_TRUE(a.valid);
    ASSERT_TRUE(b.valid);
    if (with_uv) {
        expect_near(a.duv_dx, b.duv_dx, 1e-5f, "duv_dx");
        expect_near(a.duv_dy, b.duv_dy, 1e-5f, "duv_dy");
    }
    expect_near(a.dp_dx, b.dp_dx, 1e-5f, "dp_dx");
    expect_near(a.dp_dy, b.dp_dy, 1e-5f, "dp_dy");
    expect_near(a.dn_dx, b.dn_dx, 1e-5f, "dn_dx");
    expect_near(a.dn_dy, b.dn_dy, 1e-5f, "dn_dy");
    expect_near(a.dd_dx, b.dd_dx, 1e-6f, "dd_dx");
    expect_near(a.dd_dy, b.dd_dy, 1e-6f, "dd_dy");
}

// An instance under a rotation and a scale: its footprint is that of the same shape placed
// directly with that transform (a sphere's uv follows the world's axes, so only its dp, dn
// and dd are compared).
TEST(RayDifferentials, InstanceMatchesTheShapePlacedDirectly) {
    const std::string xf =
        "<transform name=\"to_world\"><scale x=\"1.7\" y=\"0.8\" z=\"1.2\"/><rotate x=\"1\" "
        "y=\"0.3\" angle=\"25\"/><translate x=\"0.2\" y=\"-0.1\" z=\"0.3\"/></transform>";
    const std::string uniform =
        "<transform name=\"to_world\"><scale value=\"0.7\"/><rotate x=\"1\" y=\"0.3\" "
        "angle=\"25\"/><translate x=\"0.2\" y=\"-0.1\" z=\"0.3\"/></transform>";
    const std::string camera =
        camera_above("perspective", 5.f, "<float name=\"fov\" value=\"30\"/>", "", 64, 64);
    const auto group = [&](const std::string& shape, const std::string& t) {
        return "<shape type=\"shapegroup\" id=\"g\">" + shape +
               "</shape><shape type=\"instance\"><ref id=\"g\"/>" + t + "</shape>";
    };
    struct Case {
        const char* name;
        std::string direct, instanced;
        bool with_uv;
    };
    const std::string sphere =
        "<shape type=\"sphere\"><point name=\"center\" value=\"0.1,0.2,0\"/><float "
        "name=\"radius\" value=\"1\"/>";
    const Case cases[] = {
        {"rectangle", "<shape type=\"rectangle\">" + xf + "</shape>",
         group("<shape type=\"rectangle\"/>", xf), true},
        {"sphere", sphere + uniform + "</shape>", group(sphere + "</shape>", uniform), false},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const auto direct = load_scene_string(scene_xml(camera + c.direct));
        const auto instanced = load_scene_string(scene_xml(camera + c.instanced));
        int compared = 0;
        for (const Vec2 pos : {Vec2{32.5f, 32.5f}, Vec2{25.2f, 38.7f}, Vec2{40.1f, 28.3f}}) {
            Hit a, b;
            ASSERT_TRUE(footprint_hit(*direct, pos, a));
            ASSERT_TRUE(footprint_hit(*instanced, pos, b));
            expect_near(a.p, b.p, 1e-5f, "p");
            expect_same_footprint(a.footprint, b.footprint, c.with_uv);
            ++compared;
        }
        EXPECT_EQ(compared, 3);
    }
}

// Rays spawned from a hit carry no differential, and their hits (even into a Hit that held a
// footprint) have none; sensors without a film plane give no differential.
TEST(RayDifferentials, NoFootprintForSecondaryRaysAndMeters) {
    const auto scene = load_scene_string(scene_xml(
        camera_above("perspective", 3.f, "<float name=\"fov\" value=\"40\"/>", "", 16, 16) +
        "<shape type=\"sphere\"><point name=\"center\" value=\"0,0,0.5\"/><float "
        "name=\"radius\" value=\"0.4\"/></shape>" +
        rectangle(4.f)));
    Hit hit;
    ASSERT_TRUE(footprint_hit(*scene, {8.f, 8.f}, hit));
    ASSERT_TRUE(hit.footprint.valid);
    const Ray down = hit.spawn({0, 0, -1});
    EXPECT_EQ(down.differential, nullptr);
    EXPECT_EQ(hit.spawn_to({0, 0, -5}).differential, nullptr);
    ASSERT_TRUE(scene->intersect(down, hit));  // the sphere's far side, from inside
    EXPECT_FALSE(hit.footprint.valid);  // (its other fields are stale: nothing reads them)
    EXPECT_EQ(hit.footprint.light_cone, 0.f);

    const auto radiancemeter = load_scene_string(scene_xml(
        "<sensor type=\"radiancemeter\"><point name=\"origin\" value=\"0.5,0,3\"/><vector "
        "name=\"direction\" value=\"0,0,-1\"/>" +
        film(1, 1) + "</sensor>" + rectangle(4.f)));
    RayDifferential rd;
    EXPECT_FALSE(radiancemeter->sensor().sample_differential({0.5f, 0.5f}, {0.5f, 0.5f}, rd));
    const auto irradiancemeter =
        load_scene_string(scene_xml("<shape type=\"disk\"><sensor type=\"irradiancemeter\">" +
                                    film(1, 1, "<rfilter type=\"box\"/>") + "</sensor></shape>"));
    EXPECT_FALSE(irradiancemeter->sensor().sample_differential({0.5f, 0.5f}, {0.5f, 0.5f}, rd));
}

}  // namespace
