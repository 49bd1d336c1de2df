// The Embree scene over a femto scene's shapes (see embree_scene.h).
#include "accel/embree_scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "femto/bsdf.h"
#include "scene/instancing.h"

namespace femto::detail {

namespace {

void embree_error(void*, RTCError code, const char* message) {
    if (code == RTC_ERROR_NONE) return;
    std::fprintf(stderr, "embree error %d: %s\n", int(code), message ? message : "");
}

// Surfaces with a pure null material let shadow rays through.
void ignore_in_shadow_rays(const RTCFilterFunctionNArguments* args) {
    for (unsigned i = 0; i < args->N; ++i) args->valid[i] = 0;
}

// -- analytic cylinders: Embree user geometry over Shape::intersect_cylinder ------------------

void cylinder_bounds(const RTCBoundsFunctionArguments* args) {
    const auto* shape = static_cast<const Shape*>(args->geometryUserPtr);
    const Bounds3 b = cylinder_box(*shape);
    RTCBounds* out = args->bounds_o;
    out->lower_x = b.min.x, out->lower_y = b.min.y, out->lower_z = b.min.z;
    out->upper_x = b.max.x, out->upper_y = b.max.y, out->upper_z = b.max.z;
}

Ray user_ray(RTCRayN* rays, unsigned n, unsigned i) {
    Ray r;
    r.o = {RTCRayN_org_x(rays, n, i), RTCRayN_org_y(rays, n, i), RTCRayN_org_z(rays, n, i)};
    r.d = {RTCRayN_dir_x(rays, n, i), RTCRayN_dir_y(rays, n, i), RTCRayN_dir_z(rays, n, i)};
    r.tmin = RTCRayN_tnear(rays, n, i);
    r.tmax = RTCRayN_tfar(rays, n, i);
    return r;
}

void cylinder_intersect(const RTCIntersectFunctionNArguments* args) {
    const auto* shape = static_cast<const Shape*>(args->geometryUserPtr);
    RTCRayN* rays = RTCRayHitN_RayN(args->rayhit, args->N);
    RTCHitN* hits = RTCRayHitN_HitN(args->rayhit, args->N);
    for (unsigned i = 0; i < args->N; ++i) {
        if (!args->valid[i]) continue;
        float t;
        if (!shape->intersect_cylinder(user_ray(rays, args->N, i), t)) continue;
        RTCRayN_tfar(rays, args->N, i) = t;
        RTCHitN_u(hits, args->N, i) = 0.f;
        RTCHitN_v(hits, args->N, i) = 0.f;
        RTCHitN_Ng_x(hits, args->N, i) = 0.f;
        RTCHitN_Ng_y(hits, args->N, i) = 0.f;
        RTCHitN_Ng_z(hits, args->N, i) = 1.f;
        RTCHitN_primID(hits, args->N, i) = args->primID;
        RTCHitN_geomID(hits, args->N, i) = args->geomID;
        for (unsigned l = 0; l < RTC_MAX_INSTANCE_LEVEL_COUNT; ++l)
            RTCHitN_instID(hits, args->N, i, l) = args->context->instID[l];
    }
}

void cylinder_occluded(const RTCOccludedFunctionNArguments* args) {
    const auto* shape = static_cast<const Shape*>(args->geometryUserPtr);
    if (shape->bsdf() && shape->bsdf()->is_null()) return;  // null surfaces never block
    for (unsigned i = 0; i < args->N; ++i) {
        if (!args->valid[i]) continue;
        float t;
        if (shape->intersect_cylinder(user_ray(args->ray, args->N, i), t))
            RTCRayN_tfar(args->ray, args->N, i) = -kInfinity;
    }
}

}  // namespace

Bounds3 cylinder_box(const Shape& shape) {
    // The two end circles bound the tube: along world axis i a circle of radius r
    // perpendicular to n reaches r sqrt(1 - n_i^2) from its centre. Padded by the hit's
    // offset scale so that rays spawned just outside still find the surface.
    const Frame& f = shape.cylinder_frame();
    const Vec3 a = shape.cylinder_base(), b = a + f.n * shape.cylinder_length();
    const float r = shape.cylinder_radius();
    const float pad =
        2.f * kRayOffsetScale * (std::max(max_abs_component(a), max_abs_component(b)) + r);
    Bounds3 box;
    for (int i = 0; i < 3; ++i) {
        const float reach = r * std::sqrt(std::max(0.f, 1.f - f.n[i] * f.n[i])) + pad;
        box.min[i] = std::min(a[i], b[i]) - reach;
        box.max[i] = std::max(a[i], b[i]) + reach;
    }
    return box;
}

RTCDevice embree_device() {
    static RTCDevice dev = [] {
        RTCDevice d = rtcNewDevice("verbose=0");
        if (!d) throw std::runtime_error("cannot create the Embree device");
        rtcSetDeviceErrorFunction(d, embree_error, nullptr);
        return d;
    }();
    return dev;
}

// One shape's geometry, attached to `scene` as `id`; false for a shape left out (invisible).
bool EmbreeScene::attach(RTCScene scene, const Shape& shape, unsigned id, Bounds3& bounds) {
    RTCDevice dev = embree_device();
    const bool null_surface = shape.bsdf() && shape.bsdf()->is_null();
    if (null_surface && !shape.emitter() && !shape.has_media())
        return false;  // invisible: nothing to see, block or enter
    RTCGeometry geom;
    if (const auto* inst = dynamic_cast<const ShapeInstance*>(&shape)) {
        const Group& group = group_scene(inst->group());
        geom = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(geom, group.scene);
        const auto& m = inst->transform().matrix();
        float xfm[12];  // 3x4, column major
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 3; ++r) xfm[3 * c + r] = float(m[r][c]);
        rtcSetGeometryTransform(geom, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
        if (group.bounds.valid())
            for (int corner = 0; corner < 8; ++corner)
                bounds.expand(inst->transform().point(
                    {(corner & 1 ? group.bounds.max : group.bounds.min).x,
                     (corner & 2 ? group.bounds.max : group.bounds.min).y,
                     (corner & 4 ? group.bounds.max : group.bounds.min).z}));
        ++instances_;
    } else if (shape.is_cylinder()) {
        geom = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(geom, 1);
        rtcSetGeometryUserData(geom, const_cast<Shape*>(&shape));
        rtcSetGeometryBoundsFunction(geom, cylinder_bounds, nullptr);
        rtcSetGeometryIntersectFunction(geom, cylinder_intersect);
        rtcSetGeometryOccludedFunction(geom, cylinder_occluded);
        const Bounds3 box = cylinder_box(shape);
        bounds.expand(box.min);
        bounds.expand(box.max);
        ++cylinders_;
    } else if (shape.is_sphere()) {
        geom = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_SPHERE_POINT);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
        const Vec3 c = shape.sphere_center();
        v[0] = c.x, v[1] = c.y, v[2] = c.z, v[3] = shape.sphere_radius();
        bounds.expand(c - Vec3(shape.sphere_radius()));
        bounds.expand(c + Vec3(shape.sphere_radius()));
        ++spheres_;
    } else {
        const TriangleMesh& m = shape.mesh();
        geom = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                              RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                              m.positions.size()));
        std::memcpy(v, m.positions.data(), m.positions.size() * sizeof(Vec3));
        auto* idx = static_cast<uint32_t*>(
            rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                    3 * sizeof(uint32_t), m.triangle_count()));
        std::memcpy(idx, m.indices.data(), m.indices.size() * sizeof(uint32_t));
        for (const Vec3& p : m.positions) bounds.expand(p);
        triangles_ += m.triangle_count();
    }
    if (null_surface) rtcSetGeometryOccludedFilterFunction(geom, ignore_in_shadow_rays);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(scene, geom, id);
    rtcReleaseGeometry(geom);
    return true;
}

// A shapegroup's child scene, built once however many instances place it.
const EmbreeScene::Group& EmbreeScene::group_scene(const ShapeGroup& group) {
    if (auto it = groups_.find(&group); it != groups_.end()) return it->second;
    Group g;
    g.scene = rtcNewScene(embree_device());
    rtcSetSceneBuildQuality(g.scene, RTC_BUILD_QUALITY_MEDIUM);
    rtcSetSceneFlags(g.scene, robust_ ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    g.shapes.resize(group.shapes().size(), nullptr);
    for (size_t i = 0; i < group.shapes().size(); ++i)
        if (attach(g.scene, *group.shapes()[i], unsigned(i), g.bounds))
            g.shapes[i] = group.shapes()[i].get();
    rtcCommitScene(g.scene);
    return groups_.emplace(&group, std::move(g)).first->second;
}

EmbreeScene::EmbreeScene(const std::vector<std::shared_ptr<Shape>>& shapes, bool robust)
    : robust_(robust) {
    RTCDevice dev = embree_device();
    scene_ = rtcNewScene(dev);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
    rtcSetSceneFlags(scene_, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    by_geom_id_.resize(shapes.size(), nullptr);
    instance_of_geom_id_.resize(shapes.size());
    for (size_t i = 0; i < shapes.size(); ++i) {
        const Shape& shape = *shapes[i];
        if (!attach(scene_, shape, unsigned(i), bounds_)) continue;
        if (const auto* inst = dynamic_cast<const ShapeInstance*>(&shape))
            instance_of_geom_id_[i] = {inst, &groups_.at(&inst->group())};
        else
            by_geom_id_[i] = &shape;
    }
    rtcCommitScene(scene_);
    if (rtcGetDeviceError(dev) != RTC_ERROR_NONE) {
        release();
        throw std::runtime_error("Embree failed to build the scene (see the message above)");
    }
}

void EmbreeScene::release() {
    for (auto& [group, g] : groups_) rtcReleaseScene(g.scene);
    groups_.clear();
    rtcReleaseScene(scene_);
    scene_ = nullptr;
}

namespace {

/// Moves the footprint of an instance's hit, found in the group's space, to the world: uv's
/// change stays, p's is a vector, the normal's is the derivative of the normalized transformed
/// normal, and the direction's is taken from the world's unit directions.
void footprint_to_world(const Transform& to_world, const Vec3& local_normal,
                        const RayDifferential& rd, const Ray& ray, Hit& hit) {
    PixelFootprint& fp = hit.footprint;
    fp.dp_dx = to_world.vector(fp.dp_dx);
    fp.dp_dy = to_world.vector(fp.dp_dy);
    const float normal_length = length(to_world.normal(local_normal));
    const Vec3 n = hit.sh.n;
    const auto normal_change = [&](const Vec3& dn_local) {
        const Vec3 dn = to_world.normal(dn_local);
        return (dn - n * dot(n, dn)) / normal_length;
    };
    fp.dn_dx = normal_change(fp.dn_dx);
    fp.dn_dy = normal_change(fp.dn_dy);
    fp.dd_dx = rd.dx_d - ray.d;
    fp.dd_dy = rd.dy_d - ray.d;
}

}  // namespace

void EmbreeScene::fill_hit(const Ray& ray, const RTCRayHit& rh, Hit& hit) const {
    const unsigned inst_id = rh.hit.instID[0];
    if (inst_id == RTC_INVALID_GEOMETRY_ID) {
        by_geom_id_[rh.hit.geomID]->fill_hit(ray, rh.ray.tfar, rh.hit.primID, rh.hit.u, rh.hit.v,
                                             hit);
        return;
    }
    // An instance: the shape's own hit in the group's space (Embree moved the ray there without
    // normalizing its direction, so t is the same), then moved to the world.
    const Placed& placed = instance_of_geom_id_[inst_id];
    const ShapeInstance& inst = *placed.instance;
    const Transform& to_world = inst.transform();
    const Transform to_local = to_world.inverse();
    Ray local{to_local.point(ray.o), to_local.vector(ray.d), ray.tmin, ray.tmax};
    RayDifferential local_differential;
    if (ray.differential) {  // lines map to lines: the footprint is found in the group's space
        const RayDifferential& rd = *ray.differential;
        local_differential = {to_local.point(rd.dx_o), to_local.vector(rd.dx_d),
                              to_local.point(rd.dy_o), to_local.vector(rd.dy_d),
                              rd.to_pixel_centre};
        local.differential = &local_differential;
    }
    const Shape* shape = placed.group->shapes[rh.hit.geomID];
    shape->fill_hit(local, rh.ray.tfar, rh.hit.primID, rh.hit.u, rh.hit.v, hit);
    const Vec3 local_normal = hit.sh.n;
    hit.p = to_world.point(hit.p);
    hit.ng = normalize(to_world.normal(hit.ng));
    hit.sh = Frame(normalize(to_world.normal(hit.sh.n)));
    hit.dpdu = to_world.vector(hit.dpdu);  // a derivative of p: moved by the linear part
    hit.wi = hit.sh.to_local(-ray.d);
    if (hit.footprint.valid)
        footprint_to_world(to_world, local_normal, *ray.differential, ray, hit);
    // The local offset scale (a bound on each coordinate's error) stretched by the transform
    // (its largest row sum of magnitudes bounds each world coordinate's), and the rounding of
    // the transform itself.
    const auto& m = to_world.matrix();
    double stretch = 0;
    for (int r = 0; r < 3; ++r)
        stretch = std::max(stretch, std::abs(m[r][0]) + std::abs(m[r][1]) + std::abs(m[r][2]));
    hit.p_error = float(stretch * hit.p_error) + kRayOffsetScale * max_abs_component(hit.p);
}

EmbreeScene::~EmbreeScene() { release(); }

}  // namespace femto::detail
