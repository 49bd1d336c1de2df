// rectangle: Mitsuba's rectangle, [-1,1]^2 at z = 0 with normal +z, placed by `to_world`.
//
// Two triangles (0,1,2) and (2,3,0) over the corners (-1,-1), (1,-1), (1,1), (-1,1), with
// uv = ((x+1)/2, (y+1)/2) as Mitsuba's analytic rectangle parameterizes it.
#include <utility>

#include "femto/plugin.h"
#include "femto/shape.h"
#include "femto/transform.h"

namespace femto {
namespace {

class RectangleShape final : public Shape {
public:
    explicit RectangleShape(const Properties& props) : Shape(props) {
        const Transform& to_world = to_world_;

        const Vec3 corners[4] = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
        // Normals go through the inverse transpose, so they stay perpendicular to the plane
        // under non-uniform scale and shear.
        const Vec3 n = normalize(to_world.normal({0, 0, 1}));
        TriangleMesh mesh;
        for (const Vec3& c : corners) {
            mesh.positions.push_back(to_world.point(c));
            mesh.normals.push_back(n);
            mesh.uvs.push_back({(c.x + 1.f) * 0.5f, (c.y + 1.f) * 0.5f});
        }
        // A handedness flip (mirror) would turn cross(p1-p0, p2-p0) against the transformed
        // normal; reversing the winding keeps the geometric normal on the normal's side.
        if (to_world.det3() < 0)
            mesh.indices = {0, 2, 1, 2, 0, 3};
        else
            mesh.indices = {0, 1, 2, 2, 3, 0};
        set_mesh(std::move(mesh));
    }
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::RectangleShape, femto::PluginKind::Shape, "rectangle",
             "Rectangle [-1,1]^2 at z=0 with normal +z (Mitsuba convention), two triangles", {})
