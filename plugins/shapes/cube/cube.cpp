// cube: Mitsuba's cube, [-1,1]^3 placed by `to_world`.
//
// The vertex, normal, uv and triangle tables are Mitsuba 3's (src/shapes/cube.cpp): 24
// vertices (4 per face, so every face is flat and has its own uv square) and 12 triangles
// wound counter-clockwise seen from outside, so cross(p1-p0, p2-p0) points outward.
#include <cstdint>
#include <utility>

#include "femto/plugin.h"
#include "femto/shape.h"
#include "femto/transform.h"

namespace femto {
namespace {

constexpr float kVertices[24][3] = {
    {1, -1, -1}, {1, -1, 1},  {-1, -1, 1},  {-1, -1, -1},  // -y
    {1, 1, -1},  {-1, 1, -1}, {-1, 1, 1},   {1, 1, 1},     // +y
    {1, -1, -1}, {1, 1, -1},  {1, 1, 1},    {1, -1, 1},    // +x
    {1, -1, 1},  {1, 1, 1},   {-1, 1, 1},   {-1, -1, 1},   // +z
    {-1, -1, 1}, {-1, 1, 1},  {-1, 1, -1},  {-1, -1, -1},  // -x
    {1, 1, -1},  {1, -1, -1}, {-1, -1, -1}, {-1, 1, -1},   // -z
};
constexpr float kFaceNormals[6][3] = {{0, -1, 0}, {0, 1, 0},  {1, 0, 0},
                                      {0, 0, 1},  {-1, 0, 0}, {0, 0, -1}};
constexpr float kFaceUvs[4][2] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
constexpr uint32_t kTriangles[12][3] = {{0, 1, 2},    {3, 0, 2},    {4, 5, 6},    {7, 4, 6},
                                        {8, 9, 10},   {11, 8, 10},  {12, 13, 14}, {15, 12, 14},
                                        {16, 17, 18}, {19, 16, 18}, {20, 21, 22}, {23, 20, 22}};

class CubeShape final : public Shape {
public:
    explicit CubeShape(const Properties& props) : Shape(props) {
        const Transform& to_world = to_world_;

        TriangleMesh mesh;
        for (int i = 0; i < 24; ++i) {
            const float* v = kVertices[i];
            const float* n = kFaceNormals[i / 4];
            mesh.positions.push_back(to_world.point({v[0], v[1], v[2]}));
            // Inverse transpose: normals stay perpendicular to the faces under any affine map.
            mesh.normals.push_back(normalize(to_world.normal({n[0], n[1], n[2]})));
            mesh.uvs.push_back({kFaceUvs[i % 4][0], kFaceUvs[i % 4][1]});
        }
        // A handedness flip (mirror) would turn cross(p1-p0, p2-p0) inward; reversing the
        // winding keeps the geometric normal outward, on the side of the shading normals.
        const bool mirror = to_world.det3() < 0;
        for (const auto& tri : kTriangles) {
            mesh.indices.push_back(tri[0]);
            mesh.indices.push_back(mirror ? tri[2] : tri[1]);
            mesh.indices.push_back(mirror ? tri[1] : tri[2]);
        }
        set_mesh(std::move(mesh));
    }
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::CubeShape, femto::PluginKind::Shape, "cube",
             "Cube [-1,1]^3 (Mitsuba convention): 12 triangles, flat faces, outward normals", {})
