// disk: Mitsuba's disk, the unit disk at z = 0 with normal +z, placed by `to_world`.
//
// The host traces triangles and spheres only, so the disk is a triangle fan of kSegments
// triangles around the center. A regular N-gon inscribed in the circle of radius r would
// have the smaller area N/2 r^2 sin(2 pi/N) (0.01% short for N = 256), which shows up
// directly in the power of a disk emitter and in the irradiance it casts. So the polygon's
// circumradius is enlarged to
//     r' = r * sqrt(pi / (N/2 * sin(2 pi/N)))       (r' = 1.0000502 r for N = 256)
// which makes the polygon's area exactly pi r^2: the surface area, emitted power and
// area-sampling pdf equal those of the true disk, and the outline stays within 5.1e-5 r of
// the circle (r' - r = 5.0e-5 r outside at the vertices, r - r' cos(pi/N) = 2.5e-5 r inside
// at the edge midpoints).
//
// uv follows Mitsuba's polar parameterization (radius, phi / 2 pi), phi = atan2(y, x) in
// [0, 2 pi). Along the seam phi = 0 the rim vertex is duplicated (v = 0 and v = 1), and
// every triangle has its own copy of the center vertex with v at the triangle's mid angle,
// so v interpolates without wrapping through the whole [0, 1) range.
#include <cmath>
#include <cstdint>
#include <utility>

#include "femto/plugin.h"
#include "femto/shape.h"
#include "femto/transform.h"

namespace femto {
namespace {

constexpr uint32_t kSegments = 256;

class DiskShape final : public Shape {
public:
    explicit DiskShape(const Properties& props) : Shape(props) {
        const Transform& to_world = to_world_;

        constexpr double kTwoPi = 2.0 * M_PI;
        constexpr double n_seg = kSegments;
        const double circumradius = std::sqrt(M_PI / (0.5 * n_seg * std::sin(kTwoPi / n_seg)));

        const Vec3 n = normalize(to_world.normal({0, 0, 1}));
        const Vec3 center = to_world.point({0, 0, 0});
        TriangleMesh mesh;
        // Vertices [0, N): one center copy per triangle; [N, 2N]: rim, with 2N == rim 0.
        for (uint32_t i = 0; i < kSegments; ++i) {
            mesh.positions.push_back(center);
            mesh.normals.push_back(n);
            mesh.uvs.push_back({0.f, static_cast<float>((i + 0.5) / n_seg)});
        }
        for (uint32_t i = 0; i <= kSegments; ++i) {
            // The seam vertex reuses angle 0 so both rim copies have identical positions.
            const double phi = kTwoPi * (i % kSegments) / n_seg;
            const Vec3 local{static_cast<float>(circumradius * std::cos(phi)),
                             static_cast<float>(circumradius * std::sin(phi)), 0.f};
            mesh.positions.push_back(to_world.point(local));
            mesh.normals.push_back(n);
            mesh.uvs.push_back({1.f, static_cast<float>(i / n_seg)});
        }
        // Counter-clockwise seen from +z, so cross(p1-p0, p2-p0) = +z; a handedness flip
        // of to_world reverses the winding to keep the geometric normal along `n`.
        const bool mirror = to_world.det3() < 0;
        for (uint32_t i = 0; i < kSegments; ++i) {
            const uint32_t a = kSegments + i, b = kSegments + i + 1;
            mesh.indices.push_back(i);
            mesh.indices.push_back(mirror ? b : a);
            mesh.indices.push_back(mirror ? a : b);
        }
        set_mesh(std::move(mesh));
    }
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::DiskShape, femto::PluginKind::Shape, "disk",
             "Unit disk at z=0 with normal +z (Mitsuba convention), an area-preserving "
             "256-triangle fan",
             {})
