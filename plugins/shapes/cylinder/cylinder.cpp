// cylinder: an analytic open cylinder (a tube without caps), traced exactly by the host.
//
// As in Mitsuba 0.6 and 3: the centerline runs from `p0` to `p1` in object space, `radius` is
// its radius there, and `to_world` places it. Object space is a unit tube along z scaled to
// (radius, radius, |p1 - p0|) in the frame of the axis (Mitsuba's Frame, the same
// orthonormal basis as femto's), so the texture coordinates are Mitsuba's: u = phi / 2pi
// around the axis, v = z / length along it. The normals point away from the axis
// (`flip_normals` turns them inward); there are no end caps.
//
// The tube stays circular only when to_world scales the two directions across the axis
// alike and keeps them perpendicular to it: any scale along the axis is fine (it is the
// length), anything else is refused. Mitsuba 3 warns about such transforms and renders
// another shape than written; Mitsuba 0.6 silently does the same.
#include <cmath>
#include <string>

#include "femto/plugin.h"
#include "femto/shape.h"
#include "femto/transform.h"

namespace femto {
namespace {

Vec3 finite_point(const Properties& props, const std::string& name, const Vec3& def) {
    const Vec3 p = props.get_point(name, def);
    if (!is_finite(p)) props.fail(name, "the point must be finite (no NaN or infinity)");
    return p;
}

double norm3(const Vec3& v) {
    return std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
}

double dot3(const Vec3& a, const Vec3& b) {
    return double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z;
}

class CylinderShape final : public Shape {
public:
    explicit CylinderShape(const Properties& props) : Shape(props) {
        const double radius = props.get_float("radius", 1.0);
        if (!(radius > 0) || !std::isfinite(radius))
            props.fail("radius", "the radius must be positive and finite, but " +
                                     std::to_string(radius) + " was given");
        const Vec3 p0 = finite_point(props, "p0", Vec3(0.f));
        const Vec3 p1 = finite_point(props, "p1", Vec3(0, 0, 1));
        const Vec3 axis = p1 - p0;
        const double length = norm3(axis);
        if (!(length > 0))
            props.fail(props.has("p1") ? "p1" : "p0",
                       "p0 and p1 are the same point: a cylinder needs an axis of positive "
                       "length");
        const Frame local(axis / float(length));
        const auto& m = to_world_.matrix();
        if (m[3][0] != 0 || m[3][1] != 0 || m[3][2] != 0 || m[3][3] != 1)
            props.fail("to_world", "a cylinder's to_world must be affine (no projective part)");
        // The object frame's directions in the world: across the axis (s, t) and along it.
        const Vec3 s = to_world_.vector(local.s), t = to_world_.vector(local.t);
        const Vec3 n = to_world_.vector(axis);
        const double ls = norm3(s), lt = norm3(t), ln = norm3(n);
        // Scene files write matrices with ~6-7 significant digits; 1e-4 relative accepts
        // those round-offs and still rejects any visible distortion, as for the sphere.
        constexpr double kTolerance = 1e-4;
        const bool circular = ls > 0 && lt > 0 && ln > 0 && std::abs(ls - lt) <= kTolerance * ls &&
                              std::abs(dot3(s, t)) <= kTolerance * ls * lt &&
                              std::abs(dot3(s, n)) <= kTolerance * ls * ln &&
                              std::abs(dot3(t, n)) <= kTolerance * lt * ln;
        if (!circular)
            props.fail("to_world",
                       "an analytic cylinder's to_world may scale along the axis but must scale "
                       "the two directions across it alike and keep them perpendicular to it "
                       "(no shear); give p0, p1 and radius instead, or use a mesh (obj/ply)");
        Frame world;
        world.s = s / float(ls);
        world.t = t / float(lt);
        world.n = n / float(ln);
        set_cylinder(to_world_.point(p0), world, float(radius * ls), float(ln));
    }
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::CylinderShape, femto::PluginKind::Shape, "cylinder",
             "Analytic open cylinder without caps (exact intersection, uniform area sampling)",
             {{"p0", "point", "(0, 0, 0)", "start of the centerline, in object space"},
              {"p1", "point", "(0, 0, 1)", "end of the centerline, in object space"},
              {"radius", "float", "1", "radius in object space (> 0)"},
              {"to_world", "transform", "identity",
               "object-to-world transform: any scale along the axis, the same scale across it, "
               "no shear"}})
