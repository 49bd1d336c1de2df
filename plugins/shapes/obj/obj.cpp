// obj: Wavefront OBJ triangle meshes, read with tinyobjloader (Debian's libtinyobjloader-dev).
//
// Conventions follow Mitsuba's obj plugin: polygons are triangulated, a vertex is one
// distinct (position, uv, normal) index triple of the file, v is flipped (v -> 1 - v) unless
// flip_tex_coords is false, vertex normals from the file are used unless face_normals is
// set, and vertices without a normal in the file get a smooth, angle-weighted normal
// computed from the faces around their position. Materials (`mtllib`, `usemtl`) are ignored:
// the material is the shape's bsdf child.
#include <tiny_obj_loader.h>

#include <cmath>
#include <cstdint>
#include <istream>
#include <sstream>
#include <streambuf>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "femto/input_file.h"
#include "femto/log.h"
#include "femto/plugin.h"
#include "femto/shape.h"
#include "femto/transform.h"

namespace femto {
namespace {

struct IndexKey {
    int v, t, n;
    bool operator==(const IndexKey& o) const { return v == o.v && t == o.t && n == o.n; }
};
struct IndexKeyHash {
    size_t operator()(const IndexKey& k) const {
        uint64_t h = static_cast<uint32_t>(k.v);
        h = h * 0x9E3779B97F4A7C15ull ^ static_cast<uint32_t>(k.t);
        h = h * 0x9E3779B97F4A7C15ull ^ static_cast<uint32_t>(k.n);
        return static_cast<size_t>(h ^ (h >> 29));
    }
};

// Reads a string in place (tinyobjloader takes a stream; the file is already in memory).
struct MemoryStreamBuf : std::streambuf {
    explicit MemoryStreamBuf(std::string& text) {
        setg(text.data(), text.data(), text.data() + text.size());
    }
};

class ObjShape final : public Shape {
public:
    explicit ObjShape(const Properties& props) : Shape(props) {
        const std::string filename = props.get_string("filename");
        const bool face_normals = props.get_bool("face_normals", false);
        const bool flip_tex_coords = props.get_bool("flip_tex_coords", true);
        const Transform& to_world = to_world_;
        const std::string quoted = "\"" + filename + "\"";

        std::string text = InputFile(filename, props.location_of("filename")).read_rest();
        MemoryStreamBuf buffer(text);
        std::istream in(&buffer);

        tinyobj::attrib_t attrib;
        std::vector<tinyobj::shape_t> shapes;
        std::vector<tinyobj::material_t> materials;
        std::string warn, err;
        // No MaterialReader: `mtllib` lines are skipped, no .mtl file is opened.
        const bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in,
                                         /*readMatFn=*/nullptr, /*triangulate=*/true,
                                         /*default_vcols_fallback=*/false);
        if (!ok) {
            while (!err.empty() && (err.back() == '\n' || err.back() == '\r')) err.pop_back();
            props.fail("filename", "cannot read OBJ file " + quoted + ": " +
                                       (err.empty() ? std::string("parse error") : err));
        }

        const size_t n_pos = attrib.vertices.size() / 3;
        const size_t n_nrm = attrib.normals.size() / 3;
        const size_t n_tex = attrib.texcoords.size() / 2;

        TriangleMesh mesh;
        std::vector<uint32_t> position_ids;
        std::unordered_map<IndexKey, uint32_t, IndexKeyHash> vertex_of;
        bool any_uv = false, any_normal = false;
        uint64_t face_number = 0;
        std::vector<uint32_t> polygon;

        auto bad_index = [&](const char* what, int index, size_t count) {
            props.fail("filename", quoted + ": face " + std::to_string(face_number) +
                                       " refers to " + what + " " + std::to_string(index + 1) +
                                       ", but the file has " + std::to_string(count));
        };
        auto vertex = [&](const tinyobj::index_t& idx) -> uint32_t {
            if (idx.vertex_index < 0 || static_cast<size_t>(idx.vertex_index) >= n_pos)
                bad_index("vertex", idx.vertex_index, n_pos);
            if (idx.texcoord_index < -1 ||
                (idx.texcoord_index >= 0 && static_cast<size_t>(idx.texcoord_index) >= n_tex))
                bad_index("texture coordinate", idx.texcoord_index, n_tex);
            if (idx.normal_index < -1 ||
                (idx.normal_index >= 0 && static_cast<size_t>(idx.normal_index) >= n_nrm))
                bad_index("normal", idx.normal_index, n_nrm);
            const IndexKey key{idx.vertex_index, idx.texcoord_index, idx.normal_index};
            const auto found = vertex_of.find(key);
            if (found != vertex_of.end()) return found->second;
            if (mesh.positions.size() >= UINT32_MAX)
                props.fail("filename", quoted + " has more than 2^32 - 1 distinct vertices");
            const uint32_t id = static_cast<uint32_t>(mesh.positions.size());
            vertex_of.emplace(key, id);
            const size_t v = static_cast<size_t>(idx.vertex_index);
            mesh.positions.push_back({static_cast<float>(attrib.vertices[3 * v]),
                                      static_cast<float>(attrib.vertices[3 * v + 1]),
                                      static_cast<float>(attrib.vertices[3 * v + 2])});
            position_ids.push_back(static_cast<uint32_t>(v));
            Vec2 uv;
            if (idx.texcoord_index >= 0) {
                const size_t t = static_cast<size_t>(idx.texcoord_index);
                const float tv = static_cast<float>(attrib.texcoords[2 * t + 1]);
                uv = {static_cast<float>(attrib.texcoords[2 * t]), flip_tex_coords ? 1.f - tv : tv};
                if (!std::isfinite(uv.x) || !std::isfinite(uv.y))
                    props.fail("filename", quoted + ": texture coordinate " +
                                               std::to_string(t + 1) + " is not finite");
                any_uv = true;
            }
            mesh.uvs.push_back(uv);
            Vec3 n;  // zero = missing, computed later
            if (idx.normal_index >= 0) {
                const size_t k = static_cast<size_t>(idx.normal_index);
                n = {static_cast<float>(attrib.normals[3 * k]),
                     static_cast<float>(attrib.normals[3 * k + 1]),
                     static_cast<float>(attrib.normals[3 * k + 2])};
                any_normal = true;
            }
            mesh.normals.push_back(n);
            return id;
        };

        for (const tinyobj::shape_t& shape : shapes) {
            const auto& indices = shape.mesh.indices;
            size_t offset = 0;
            for (const auto fv : shape.mesh.num_face_vertices) {
                ++face_number;
                const size_t count = fv;
                if (offset + count > indices.size())
                    props.fail("filename", quoted + ": inconsistent face list (face " +
                                               std::to_string(face_number) + ")");
                polygon.clear();
                for (size_t k = 0; k < count; ++k) polygon.push_back(vertex(indices[offset + k]));
                // tinyobjloader already triangulated; a fan covers any polygon it kept.
                for (size_t k = 1; k + 1 < polygon.size(); ++k) {
                    mesh.indices.push_back(polygon[0]);
                    mesh.indices.push_back(polygon[k]);
                    mesh.indices.push_back(polygon[k + 1]);
                }
                offset += count;
            }
        }
        if (mesh.indices.empty())
            props.fail("filename", quoted +
                                       " contains no faces (a mesh needs at least one "
                                       "triangle)");
        for (size_t i = 0; i < mesh.positions.size(); ++i)
            if (!is_finite(mesh.positions[i]))
                props.fail("filename", quoted + ": vertex " + std::to_string(position_ids[i] + 1) +
                                           " has a non-finite coordinate");
        // tinyobjloader's warnings, once the file is known to be usable. Those about
        // materials are dropped: materials are ignored on purpose (see the top of this file).
        std::istringstream warnings(warn);
        for (std::string line; std::getline(warnings, line);) {
            while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
            if (!line.empty() && line.find("material") == std::string::npos &&
                line.find(".mtl") == std::string::npos)
                log_warning(props.location_of("filename"), quoted + ": " + line);
        }
        if (!any_uv) mesh.uvs.clear();
        if (!any_normal) mesh.normals.clear();
        mesh_to_world(mesh, position_ids, n_pos, to_world, face_normals);
        set_mesh(std::move(mesh));
    }
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::ObjShape, femto::PluginKind::Shape, "obj",
             "Wavefront OBJ triangle mesh (polygons triangulated, materials ignored)",
             {{"filename", "filename", "", "path of the .obj file (relative to the scene file)"},
              {"face_normals", "boolean", "false",
               "ignore vertex normals and shade with the flat face normals"},
              {"flip_tex_coords", "boolean", "true", "use v -> 1 - v (Mitsuba's default)"}})
