// Tests of the serialized shape plugin (Mitsuba's .serialized meshes, read with zlib): files
// written here in versions 3 and 4, single and double precision, with and without normals,
// uvs and colours, one or several meshes, read back exactly; then corrupt files (bad header,
// truncation at every length, flipped bytes, counts the data cannot hold, indices out of
// range, a bad shape_index) give a located femto::SceneError naming the file, never a crash.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "femto/error.h"
#include "femto/host.h"
#include "femto/shape.h"
#include "femto/testing/render.h"
#include "shape_test_util.h"

namespace {

using femto::Properties;
using femto::Shape;
using femto::Vec2;
using femto::Vec3;
using femto_shape_test::make_shape;
using femto_shape_test::ScratchDir;

// A unit square of two triangles at z = 0.5 with normals +z and uvs at its corners.
const std::vector<Vec3> kPositions = {{0, 0, 0.5f}, {1, 0, 0.5f}, {1, 1, 0.5f}, {0, 1, 0.5f}};
const std::vector<Vec2> kUvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
const std::vector<uint32_t> kIndices = {0, 1, 2, 0, 2, 3};

struct MeshOptions {
    int version = 4;
    bool wide = false, normals = true, uvs = true, colours = false, face_normals = false;
    float shift = 0;  // added to every x, to tell the meshes of one file apart
    std::vector<uint32_t> indices = kIndices;
    uint64_t vertex_count = 4;  // as the header states it
};

template <typename T>
void put(std::string& out, T v) {
    out.append(reinterpret_cast<const char*>(&v), sizeof v);
}

void put_real(std::string& out, float v, bool wide) {
    if (wide)
        put<double>(out, double(v));
    else
        put<float>(out, v);
}

// One mesh: the uncompressed header and the zlib stream.
std::string write_mesh(const MeshOptions& o) {
    std::string body;
    uint32_t flags = o.wide ? 0x2000 : 0x1000;
    if (o.normals) flags |= 0x1;
    if (o.uvs) flags |= 0x2;
    if (o.colours) flags |= 0x8;
    if (o.face_normals) flags |= 0x10;
    put<uint32_t>(body, flags);
    if (o.version >= 4) body += std::string("square") + '\0';
    put<uint64_t>(body, o.vertex_count);
    put<uint64_t>(body, o.indices.size() / 3);
    for (const Vec3& p : kPositions)
        for (float c : {p.x + o.shift, p.y, p.z}) put_real(body, c, o.wide);
    if (o.normals)
        for (size_t i = 0; i < kPositions.size(); ++i)
            for (float c : {0.f, 0.f, 1.f}) put_real(body, c, o.wide);
    if (o.uvs)
        for (const Vec2& uv : kUvs)
            for (float c : {uv.x, uv.y}) put_real(body, c, o.wide);
    if (o.colours)
        for (size_t i = 0; i < kPositions.size() * 3; ++i) put_real(body, 0.25f, o.wide);
    for (uint32_t i : o.indices) put<uint32_t>(body, i);
    uLongf size = compressBound(uLong(body.size()));
    std::string packed(size, '\0');
    EXPECT_EQ(compress(reinterpret_cast<Bytef*>(packed.data()), &size,
                       reinterpret_cast<const Bytef*>(body.data()), uLong(body.size())),
              Z_OK);
    packed.resize(size);
    std::string out;
    put<uint16_t>(out, 0x041C);
    put<uint16_t>(out, uint16_t(o.version));
    return out + packed;
}

// Several meshes and the end-of-file dictionary of their offsets.
std::string write_file(const std::vector<MeshOptions>& meshes) {
    std::string out;
    std::vector<uint64_t> offsets;
    for (const MeshOptions& o : meshes) {
        offsets.push_back(out.size());
        out += write_mesh(o);
    }
    for (uint64_t offset : offsets)
        if (meshes[0].version >= 4)
            put<uint64_t>(out, offset);
        else
            put<uint32_t>(out, uint32_t(offset));
    put<uint32_t>(out, uint32_t(meshes.size()));
    return out;
}

std::shared_ptr<Shape> load(const std::string& file, int64_t index = 0) {
    Properties props("serialized", {});
    props.set_string("filename", file);
    if (index != 0) props.set_int("shape_index", index);
    return make_shape(props);
}

std::string load_error(const std::string& file, int64_t index = 0) {
    try {
        load(file, index);
    } catch (const femto::SceneError& e) {
        return e.what();
    }
    ADD_FAILURE() << "no error for " << file;
    return {};
}

void expect_square(const femto::TriangleMesh& m, float shift, bool normals, bool uvs) {
    ASSERT_EQ(m.positions.size(), kPositions.size());
    for (size_t i = 0; i < kPositions.size(); ++i) {
        EXPECT_EQ(m.positions[i].x, kPositions[i].x + shift) << i;
        EXPECT_EQ(m.positions[i].y, kPositions[i].y) << i;
        EXPECT_EQ(m.positions[i].z, kPositions[i].z) << i;
    }
    EXPECT_EQ(m.indices, kIndices);
    EXPECT_EQ(m.normals.size(), normals ? kPositions.size() : 0u);
    for (const Vec3& n : m.normals) EXPECT_EQ(n.z, 1.f);
    ASSERT_EQ(m.uvs.size(), uvs ? kUvs.size() : 0u);
    for (size_t i = 0; i < m.uvs.size(); ++i) {
        EXPECT_EQ(m.uvs[i].x, kUvs[i].x) << i;
        EXPECT_EQ(m.uvs[i].y, kUvs[i].y) << i;
    }
}

TEST(Serialized, ReadsEveryVariantExactly) {
    ScratchDir dir;
    for (const int version : {3, 4})
        for (const bool wide : {false, true})
            for (const bool extras : {false, true}) {
                SCOPED_TRACE("version " + std::to_string(version) + (wide ? ", double" : "") +
                             (extras ? ", normals, uvs, colours" : ""));
                MeshOptions o;
                o.version = version, o.wide = wide;
                o.normals = o.uvs = o.colours = extras;
                auto shape = load(dir.write("m.serialized", write_file({o})));
                ASSERT_TRUE(shape);
                // Without normals in the file, smooth ones are computed (all +z here).
                expect_square(shape->mesh(), 0, true, extras);
                EXPECT_FLOAT_EQ(shape->surface_area(), 1.f);
            }
    // The face-normals flag shades flat, as face_normals=true does.
    MeshOptions flat;
    flat.face_normals = true;
    auto shape = load(dir.write("flat.serialized", write_file({flat})));
    ASSERT_TRUE(shape);
    expect_square(shape->mesh(), 0, false, true);
}

TEST(Serialized, RendersAsTheSameMeshFromAnObjFile) {
    // The square as .serialized and as .obj (same vertices, triangles, normals, uvs), lit
    // from above, seen through an orthographic camera: the same image from the same seed.
    ScratchDir dir;
    const std::string serialized = dir.write("square.serialized", write_file({MeshOptions{}}));
    const std::string obj =
        dir.write("square.obj",
                  "v 0 0 0.5\nv 1 0 0.5\nv 1 1 0.5\nv 0 1 0.5\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                  "vn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n");
    auto render = [](const std::string& type, const std::string& file) {
        auto scene = femto::load_scene_string(
            "<scene version=\"3.0.0\"><integrator type=\"path\"/><sensor "
            "type=\"orthographic\"><transform name=\"to_world\"><lookat origin=\"0.5,0.5,3\" "
            "target=\"0.5,0.5,0\" up=\"0,1,0\"/></transform><sampler type=\"independent\">"
            "<integer name=\"sample_count\" value=\"4\"/></sampler><film type=\"hdrfilm\">"
            "<integer name=\"width\" value=\"16\"/><integer name=\"height\" value=\"16\"/>"
            "</film></sensor><emitter type=\"point\"><point name=\"position\" "
            "value=\"0.3,0.6,2\"/></emitter><shape type=\"" +
            type + "\"><string name=\"filename\" value=\"" + file + "\"/></shape></scene>");
        return femto::testing::render_steady(*scene, 9);
    };
    femto::testing::expect_same_image(render("obj", obj), render("serialized", serialized), "obj",
                                      "serialized");
}

TEST(Serialized, ShapeIndexPicksAMeshOfSeveral) {
    ScratchDir dir;
    for (const int version : {3, 4}) {
        SCOPED_TRACE("version " + std::to_string(version));
        std::vector<MeshOptions> meshes(3);
        for (int i = 0; i < 3; ++i)
            meshes[size_t(i)].version = version, meshes[size_t(i)].shift = float(10 * i);
        meshes[1].wide = true;
        const std::string file = dir.write("many.serialized", write_file(meshes));
        for (int i = 0; i < 3; ++i) {
            auto shape = load(file, i);
            ASSERT_TRUE(shape);
            expect_square(shape->mesh(), float(10 * i), true, true);
        }
        EXPECT_NE(load_error(file, 3).find("shape_index 3 is out of range: the file holds 3"),
                  std::string::npos);
    }
}

TEST(Serialized, CorruptFilesGiveLocatedErrors) {
    ScratchDir dir;
    const std::string good = write_file({MeshOptions{}});
    auto error_for = [&](const std::string& bytes) {
        return load_error(dir.write("bad.serialized", bytes));
    };
    std::string bytes = good;
    bytes[0] = 'X';
    EXPECT_NE(error_for(bytes).find("not a Mitsuba serialized mesh"), std::string::npos);
    bytes = good;
    bytes[2] = 9;
    EXPECT_NE(error_for(bytes).find("file version 9 is not 3 or 4"), std::string::npos);
    MeshOptions bad_index;
    bad_index.indices = {0, 1, 7};
    EXPECT_NE(error_for(write_file({bad_index})).find("triangle 0 (0-based) uses vertex 7 of 4"),
              std::string::npos);
    // A count no compressed data of this size can hold fails before anything is allocated.
    MeshOptions huge;
    huge.vertex_count = uint64_t(1) << 31;
    EXPECT_NE(error_for(write_file({huge})).find("cannot come from"), std::string::npos);
    // Every truncation and random byte flips: a SceneError naming the file, never a crash.
    const std::string mesh = write_mesh(MeshOptions{});
    for (size_t n = 0; n < mesh.size(); ++n) {
        const std::string msg = error_for(mesh.substr(0, n));
        EXPECT_NE(msg.find("bad.serialized"), std::string::npos) << n << ": " << msg;
    }
    std::mt19937 rng(3);
    int errors = 0;
    for (int trial = 0; trial < 300; ++trial) {
        bytes = good;
        for (int k = 0; k < 3; ++k) bytes[rng() % bytes.size()] = static_cast<char>(rng() & 0xff);
        try {
            load(dir.write("flip.serialized", bytes));
        } catch (const femto::SceneError& e) {
            // The reader names the file; a mesh it read whole may still fail the shape's own
            // checks (zero area, coordinates out of range), located at the shape.
            ++errors;
            EXPECT_FALSE(std::string(e.what()).empty());
        }
    }
    EXPECT_GT(errors, 0);
    EXPECT_NE(load_error(dir.path("missing.serialized")).find("missing.serialized"),
              std::string::npos);
}

}  // namespace
