// Shared mesh post-processing for mesh-file shapes (see femto/shape.h).
#include <cmath>
#include <numeric>

#include "femto/shape.h"

namespace femto {

void mesh_to_world(TriangleMesh& mesh, const std::vector<uint32_t>& position_ids,
                   size_t position_count, const Transform& to_world, bool face_normals) {
    for (Vec3& p : mesh.positions) p = to_world.point(p);
    if (to_world.det3() < 0)
        for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
            std::swap(mesh.indices[t + 1], mesh.indices[t + 2]);
    if (face_normals) {
        mesh.normals.clear();
        return;
    }
    const size_t nv = mesh.positions.size();
    std::vector<bool> missing(nv, true);
    bool any_missing = false;
    if (mesh.normals.size() == nv) {
        for (size_t i = 0; i < nv; ++i) {
            Vec3 n = to_world.normal(mesh.normals[i]);
            const float m = max_abs_component(n);
            if (m > 0 && std::isfinite(m)) {
                n = n / m;  // rescale first: no overflow/underflow in the length
                mesh.normals[i] = n / length(n);
                missing[i] = false;
            } else {
                any_missing = true;
            }
        }
    } else {
        mesh.normals.assign(nv, Vec3());
        any_missing = true;
    }
    if (!any_missing) return;

    std::vector<Vec3> accum(position_count), fallback(position_count);
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        const uint32_t idx[3] = {mesh.indices[t], mesh.indices[t + 1], mesh.indices[t + 2]};
        const Vec3 p[3] = {mesh.positions[idx[0]], mesh.positions[idx[1]], mesh.positions[idx[2]]};
        Vec3 fn = cross(p[1] - p[0], p[2] - p[0]);
        const float len = length(fn);
        if (!(len > 0) || !std::isfinite(len)) continue;  // degenerate: no orientation
        fn = fn / len;
        for (int k = 0; k < 3; ++k) {
            const Vec3 e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
            const float l1 = length(e1), l2 = length(e2);
            if (!(l1 > 0) || !(l2 > 0)) continue;
            const float angle = std::acos(clamp(dot(e1, e2) / (l1 * l2), -1.f, 1.f));
            const uint32_t g = position_ids[idx[k]];
            accum[g] += fn * angle;
            if (squared_length(fallback[g]) == 0) fallback[g] = fn;
        }
    }
    for (size_t i = 0; i < nv; ++i) {
        if (!missing[i]) continue;
        const uint32_t g = position_ids[i];
        const float len = length(accum[g]);
        if (len > 0 && std::isfinite(len))
            mesh.normals[i] = accum[g] / len;
        else if (squared_length(fallback[g]) > 0)  // adjacent normals cancel out exactly
            mesh.normals[i] = fallback[g];
        else  // only on degenerate triangles, which are never hit: any unit vector will do
            mesh.normals[i] = Vec3(0, 0, 1);
    }
}

void mesh_to_world(TriangleMesh& mesh, const Transform& to_world, bool face_normals) {
    std::vector<uint32_t> ids(mesh.positions.size());
    std::iota(ids.begin(), ids.end(), 0u);
    mesh_to_world(mesh, ids, ids.size(), to_world, face_normals);
}

}  // namespace femto
