// sphere: an analytic sphere (traced exactly by the host, not tessellated).
//
// As in Mitsuba, `center` and `radius` describe the sphere in object space and `to_world`
// places it: the world center is to_world(center) and the radius is scaled by the transform's
// scale factor. An analytic sphere stays a sphere only under a similarity transform, so a
// non-uniform scale, a shear or a projective transform is rejected.
#include <cmath>
#include <string>

#include "femto/plugin.h"
#include "femto/shape.h"
#include "femto/transform.h"

namespace femto {
namespace {

/// The scale factor of `t` when its linear part is a uniform scale times a rotation (or a
/// mirror), or throws a located error.
double uniform_scale(const Properties& props, const Transform& t) {
    const auto& m = t.matrix();
    if (m[3][0] != 0 || m[3][1] != 0 || m[3][2] != 0 || m[3][3] != 1)
        props.fail("to_world", "a sphere's to_world must be affine (no projective part)");
    // Columns of the 3x3 part: for s * R they are orthogonal and all of length s.
    double col[3][3];
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) col[j][i] = m[i][j];
    auto dotc = [&](int a, int b) {
        return col[a][0] * col[b][0] + col[a][1] * col[b][1] + col[a][2] * col[b][2];
    };
    const double s2 = (dotc(0, 0) + dotc(1, 1) + dotc(2, 2)) / 3.0;
    // Scene files write matrices with ~6-7 significant digits; 1e-4 relative accepts those
    // round-offs and still rejects any visible non-uniformity (0.01% of the radius).
    constexpr double kTolerance = 1e-4;
    bool uniform = s2 > 0;
    for (int a = 0; a < 3 && uniform; ++a)
        for (int b = 0; b < 3; ++b) {
            const double expected = a == b ? s2 : 0.0;
            if (std::abs(dotc(a, b) - expected) > 2 * kTolerance * s2) uniform = false;
        }
    if (!uniform)
        props.fail("to_world",
                   "an analytic sphere supports only a uniform scale in to_world (translation, "
                   "rotation and the same scale on every axis); for an ellipsoid, give the "
                   "radius and center instead of scaling, or use a mesh (obj/ply) with this "
                   "transform");
    return std::sqrt(s2);
}

class SphereShape final : public Shape {
public:
    explicit SphereShape(const Properties& props) : Shape(props) {
        Vec3 center = props.get_point("center", Vec3(0.f));
        double radius = props.get_float("radius", 1.0);
        if (!(radius > 0))
            props.fail("radius",
                       "the radius must be positive, but " + std::to_string(radius) + " was given");
        radius *= uniform_scale(props, to_world_);
        center = to_world_.point(center);
        set_sphere(center, static_cast<float>(radius));
    }
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::SphereShape, femto::PluginKind::Shape, "sphere",
             "Analytic sphere (exact intersection and visible-cone sampling)",
             {{"center", "point", "(0, 0, 0)", "center in object space"},
              {"radius", "float", "1", "radius in object space (> 0)"},
              {"to_world", "transform", "identity",
               "object-to-world transform: translation, rotation and uniform scale only"}})
