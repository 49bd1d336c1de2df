// Helpers shared by test_shapes.cpp, test_emitters.cpp and test_ply.cpp: building shape and
// emitter plugins, a brute-force ray caster that produces host hit records through
// Shape::fill_hit (as the Embree scene does), and a scratch directory.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <random>
#include <string>

#include "femto/emitter.h"
#include "femto/host.h"
#include "femto/math.h"
#include "femto/properties.h"
#include "femto/scene.h"
#include "femto/shape.h"

namespace femto_shape_test {

inline std::shared_ptr<femto::Shape> make_shape(const femto::Properties& props) {
    femto::ObjectPtr obj =
        femto::create_object(femto::PluginKind::Shape, props.plugin_type(), props);
    if (!obj || obj->kind() != femto::PluginKind::Shape) {
        ADD_FAILURE() << "plugin " << props.plugin_type() << " did not build a shape";
        return nullptr;
    }
    return std::static_pointer_cast<femto::Shape>(obj);
}

inline std::shared_ptr<femto::Emitter> make_emitter(const femto::Properties& props) {
    femto::ObjectPtr obj =
        femto::create_object(femto::PluginKind::Emitter, props.plugin_type(), props);
    if (!obj || obj->kind() != femto::PluginKind::Emitter) {
        ADD_FAILURE() << "plugin " << props.plugin_type() << " did not build an emitter";
        return nullptr;
    }
    return std::static_pointer_cast<femto::Emitter>(obj);
}

/// Closest intersection of `ray` with `shape` by testing every triangle (Moller-Trumbore in
/// double precision; Embree's barycentrics: p = (1-u-v) p0 + u p1 + v p2) or the analytic
/// sphere, then Shape::fill_hit as the host's scene does. Cylinders go through the host's own
/// Shape::intersect_cylinder (what its Embree user geometry calls; test_cylinder.cpp checks it
/// against closed forms). Returns false on a miss.
inline bool brute_intersect(const femto::Shape& shape, const femto::Ray& ray, femto::Hit& hit) {
    if (shape.is_cylinder()) {
        float t = 0;
        if (!shape.intersect_cylinder(ray, t) || !(t > ray.tmin)) return false;
        shape.fill_hit(ray, t, 0, 0.f, 0.f, hit);
        return true;
    }
    double best_t = ray.tmax;
    uint32_t best_prim = 0;
    double best_u = 0, best_v = 0;
    bool found = false;
    const double o[3] = {ray.o.x, ray.o.y, ray.o.z}, d[3] = {ray.d.x, ray.d.y, ray.d.z};
    if (shape.is_sphere()) {
        const femto::Vec3 c = shape.sphere_center();
        const double oc[3] = {o[0] - c.x, o[1] - c.y, o[2] - c.z};
        const double a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        const double b = 2 * (oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2]);
        const double r = shape.sphere_radius();
        const double cc = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - r * r;
        const double disc = b * b - 4 * a * cc;
        if (disc < 0) return false;
        const double sq = std::sqrt(disc);
        for (const double t : {(-b - sq) / (2 * a), (-b + sq) / (2 * a)})
            if (t > ray.tmin && t < best_t) {
                best_t = t;
                found = true;
                break;
            }
    } else {
        const femto::TriangleMesh& m = shape.mesh();
        for (uint32_t i = 0; i < m.triangle_count(); ++i) {
            const femto::Vec3 p0 = m.positions[m.indices[3 * i]];
            const femto::Vec3 p1 = m.positions[m.indices[3 * i + 1]];
            const femto::Vec3 p2 = m.positions[m.indices[3 * i + 2]];
            const double e1[3] = {p1.x - double(p0.x), p1.y - double(p0.y), p1.z - double(p0.z)};
            const double e2[3] = {p2.x - double(p0.x), p2.y - double(p0.y), p2.z - double(p0.z)};
            const double pv[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2],
                                  d[0] * e2[1] - d[1] * e2[0]};
            const double det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
            if (std::abs(det) < 1e-300) continue;
            const double inv = 1.0 / det;
            const double tv[3] = {o[0] - p0.x, o[1] - p0.y, o[2] - p0.z};
            const double u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) * inv;
            if (u < 0 || u > 1) continue;
            const double qv[3] = {tv[1] * e1[2] - tv[2] * e1[1], tv[2] * e1[0] - tv[0] * e1[2],
                                  tv[0] * e1[1] - tv[1] * e1[0]};
            const double v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) * inv;
            if (v < 0 || u + v > 1) continue;
            const double t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) * inv;
            if (t > ray.tmin && t < best_t) {
                best_t = t;
                best_prim = i;
                best_u = u;
                best_v = v;
                found = true;
            }
        }
    }
    if (!found) return false;
    shape.fill_hit(ray, float(best_t), best_prim, float(best_u), float(best_v), hit);
    return true;
}

/// A ray from `from` toward `to` (unit direction).
inline femto::Ray ray_toward(const femto::Vec3& from, const femto::Vec3& to) {
    return femto::Ray{from, femto::normalize(to - from), 0.f, femto::kInfinity};
}

inline ::testing::AssertionResult vec_near(const femto::Vec3& a, const femto::Vec3& b, double tol) {
    for (int k = 0; k < 3; ++k)
        if (!(std::abs(double(a[k]) - double(b[k])) <= tol))
            return ::testing::AssertionFailure()
                   << "(" << a.x << ", " << a.y << ", " << a.z << ") != (" << b.x << ", " << b.y
                   << ", " << b.z << ") +- " << tol;
    return ::testing::AssertionSuccess();
}

/// A fresh directory under the system temp dir, removed with its contents at the end.
class ScratchDir {
public:
    ScratchDir() {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        std::string name = "femto_test_";
        if (info) name += std::string(info->test_suite_name()) + "_" + info->name() + "_";
        name += std::to_string(::getpid());
        path_ = std::filesystem::temp_directory_path() / name;
        std::filesystem::remove_all(path_);
        std::filesystem::create_directories(path_);
    }
    ~ScratchDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;

    /// Writes `content` to `name` in this directory and returns the absolute path.
    std::string write(const std::string& name, const std::string& content) const {
        const std::filesystem::path p = path_ / name;
        std::ofstream out(p, std::ios::binary);
        out.write(content.data(), std::streamsize(content.size()));
        return p.string();
    }
    std::string path(const std::string& name) const { return (path_ / name).string(); }

private:
    std::filesystem::path path_;
};

/// The scales a ray-offset test runs at: sizes 1e-6 ... 1e6, centred at the origin and 1e3
/// sizes away from it (up to 1e8). `run(size, centre)` is called under a SCOPED_TRACE.
inline void for_each_scale(const std::function<void(double, const femto::Vec3&)>& run) {
    for (int k = -6; k <= 6; k += 3)
        for (const double away : {0.0, 1e3}) {
            const double size = std::pow(10.0, k);
            if (away * size > 1e8) continue;
            SCOPED_TRACE("size 1e" + std::to_string(k) + ", " + std::to_string(away) + " away");
            run(size, femto::Vec3(float(away * size), float(-0.5 * away * size),
                                  float(0.25 * away * size)));
        }
}

/// Rays leaving a surface at scale `size` around `centre`: 4000 rays from a sphere of radius
/// 3 size aimed within 0.5 size of the centre; at each hit, a ray leaves outward (a random
/// direction on the geometric normal's side) and must find nothing, and a ray leaves inward
/// (its opposite), whose hit (if any) `inward(hit, again, in)` judges: true when it is the
/// surface hitting itself. Returns the number of hits; self hits are test failures.
inline int expect_rays_leave(
    const femto::Scene& scene, const femto::Vec3& centre, double size,
    const std::function<bool(const femto::Hit&, const femto::Hit*, const femto::Vec3&)>& inward) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    auto unit = [&] {
        const float z = 2 * u(rng) - 1, phi = 2 * femto::kPi * u(rng), r = std::sqrt(1 - z * z);
        return femto::Vec3(r * std::cos(phi), r * std::sin(phi), z);
    };
    int hits = 0, self_hits = 0;
    for (int i = 0; i < 4000; ++i) {
        const femto::Vec3 from = centre + unit() * float(3 * size);
        const femto::Vec3 aim = centre + unit() * float(0.5 * size * u(rng));
        femto::Hit hit;
        if (!scene.intersect(femto::Ray{from, femto::normalize(aim - from), 0.f, femto::kInfinity},
                             hit))
            continue;
        ++hits;
        femto::Vec3 out = unit();
        if (femto::dot(out, hit.ng) < 0) out = -out;
        femto::Hit again;
        if (scene.intersect(hit.spawn(out), again)) ++self_hits;
        const bool found = scene.intersect(hit.spawn(-out), again);
        if (inward(hit, found ? &again : nullptr, -out)) ++self_hits;
    }
    EXPECT_EQ(self_hits, 0);
    return hits;
}

}  // namespace femto_shape_test
