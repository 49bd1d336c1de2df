// Tests of the ply shape plugin's own PLY reader: the same known mesh written by the test in
// ascii, binary little endian and binary big endian (with extra properties and elements the
// reader must skip, lists included) reads back exactly; then malformed files (bad headers,
// absurd counts, out-of-range indices, every truncation of a binary file, random byte
// corruption) must give a femto::SceneError naming the file, never a crash.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "femto/error.h"
#include "femto/host.h"
#include "femto/shape.h"
#include "femto/transform.h"
#include "shape_test_util.h"

namespace {

using femto::Properties;
using femto::Shape;
using femto::Transform;
using femto::TriangleMesh;
using femto::Vec2;
using femto::Vec3;
using femto_shape_test::make_shape;
using femto_shape_test::ScratchDir;
using femto_shape_test::vec_near;

// -- a small PLY writer -----------------------------------------------------------------------

struct Prop {
    std::string type, name;
    std::string count_type;  ///< non-empty for a list
};
struct Element {
    std::string name;
    std::vector<Prop> props;
    /// items[i][p]: the values of property p of item i (one for a scalar, n for a list).
    std::vector<std::vector<std::vector<double>>> items;
};

enum class Format { Ascii, Little, Big };

template <typename T>
void put(std::string& out, double v, bool big) {
    const T x = static_cast<T>(v);
    unsigned char b[sizeof(T)];
    std::memcpy(b, &x, sizeof(T));
    if (big != (std::endian::native == std::endian::big))
        for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    out.append(reinterpret_cast<const char*>(b), sizeof(T));
}

void put_value(std::string& out, const std::string& type, double v, Format f) {
    if (f == Format::Ascii) {
        std::ostringstream s;
        s.precision(17);
        s << v << ' ';
        out += s.str();
        return;
    }
    const bool big = f == Format::Big;
    if (type == "char" || type == "int8") put<int8_t>(out, v, big);
    if (type == "uchar" || type == "uint8") put<uint8_t>(out, v, big);
    if (type == "short" || type == "int16") put<int16_t>(out, v, big);
    if (type == "ushort" || type == "uint16") put<uint16_t>(out, v, big);
    if (type == "int" || type == "int32") put<int32_t>(out, v, big);
    if (type == "uint" || type == "uint32") put<uint32_t>(out, v, big);
    if (type == "float" || type == "float32") put<float>(out, v, big);
    if (type == "double" || type == "float64") put<double>(out, v, big);
}

std::string write_ply(const std::vector<Element>& elements, Format f) {
    std::string out = "ply\n";
    out += f == Format::Ascii    ? "format ascii 1.0\n"
           : f == Format::Little ? "format binary_little_endian 1.0\n"
                                 : "format binary_big_endian 1.0\n";
    out += "comment written by femto's tests\nobj_info nothing\n";
    for (const Element& e : elements) {
        out += "element " + e.name + " " + std::to_string(e.items.size()) + "\n";
        for (const Prop& p : e.props)
            out += p.count_type.empty()
                       ? "property " + p.type + " " + p.name + "\n"
                       : "property list " + p.count_type + " " + p.type + " " + p.name + "\n";
    }
    out += "end_header\n";
    for (const Element& e : elements)
        for (const auto& item : e.items) {
            for (size_t p = 0; p < e.props.size(); ++p) {
                if (!e.props[p].count_type.empty())
                    put_value(out, e.props[p].count_type, double(item[p].size()), f);
                for (const double v : item[p]) put_value(out, e.props[p].type, v, f);
            }
            if (f == Format::Ascii) out += "\n";
        }
    return out;
}

// The known mesh: a square pyramid (a quad base and four triangles), 5 vertices with unit
// normals and uvs. All values are exact in float.
const std::vector<Vec3> kPositions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.5f, 1}};
const std::vector<Vec3> kNormals = {
    {0, 0, 1}, {0, 0.6f, 0.8f}, {0.6f, 0, 0.8f}, {0.8f, 0.6f, 0}, {0, 1, 0}};
const std::vector<Vec2> kUvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5f, 0.25f}};
const std::vector<std::vector<double>> kFaces = {
    {0, 3, 2, 1}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
// Fan triangulation of kFaces.
const std::vector<uint32_t> kIndices = {0, 3, 2, 0, 2, 1, 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};

struct MeshOptions {
    std::string count_type = "uchar", index_type = "int";
    std::string u = "u", v = "v";
    std::string position_type = "float";
    bool normals = true, uvs = true, extras = true;
};

std::vector<Element> pyramid(const MeshOptions& o = {}) {
    Element vertex{"vertex", {}, {}};
    vertex.props = {
        {o.position_type, "x", ""}, {o.position_type, "y", ""}, {o.position_type, "z", ""}};
    if (o.extras) vertex.props.push_back({"double", "confidence", ""});
    if (o.normals)
        for (const char* n : {"nx", "ny", "nz"}) vertex.props.push_back({"float", n, ""});
    if (o.uvs) {
        vertex.props.push_back({"float", o.u, ""});
        vertex.props.push_back({"float", o.v, ""});
    }
    if (o.extras)
        for (const char* c : {"red", "green", "blue"}) vertex.props.push_back({"uchar", c, ""});
    for (size_t i = 0; i < kPositions.size(); ++i) {
        std::vector<std::vector<double>> item = {
            {kPositions[i].x}, {kPositions[i].y}, {kPositions[i].z}};
        if (o.extras) item.push_back({0.125 * double(i)});
        if (o.normals)
            for (int k = 0; k < 3; ++k) item.push_back({kNormals[i][k]});
        if (o.uvs) {
            item.push_back({kUvs[i].x});
            item.push_back({kUvs[i].y});
        }
        if (o.extras)
            for (int k = 0; k < 3; ++k) item.push_back({double(40 * i + k)});
        vertex.items.push_back(item);
    }
    Element material{"material",
                     {{"float", "weights", "uchar"}, {"int", "id", ""}},
                     {{{0.5, 0.25, 0.125}, {7}}, {{}, {-3}}}};
    Element face{"face", {}, {}};
    if (o.extras) face.props.push_back({"uchar", "flags", ""});
    face.props.push_back({o.index_type, "vertex_indices", o.count_type});
    if (o.extras) {
        face.props.push_back({"float", "texcoord", "uint"});
        face.props.push_back({"int", "extra", ""});
    }
    for (size_t f = 0; f < kFaces.size(); ++f) {
        std::vector<std::vector<double>> item;
        if (o.extras) item.push_back({double(f)});
        item.push_back(kFaces[f]);
        if (o.extras) {
            item.push_back(std::vector<double>(2 * kFaces[f].size(), 0.5));
            item.push_back({-double(f)});
        }
        face.items.push_back(item);
    }
    std::vector<Element> out = {vertex};
    if (o.extras) out.push_back(material);
    out.push_back(face);
    if (o.extras)
        out.push_back(Element{
            "edge", {{"int", "vertex1", ""}, {"int", "vertex2", ""}}, {{{0}, {1}}, {{1}, {2}}}});
    return out;
}

std::shared_ptr<Shape> load(const std::string& file) {
    Properties props("ply", {});
    props.set_string("filename", file);
    return make_shape(props);
}

void expect_pyramid(const TriangleMesh& m, bool normals = true, bool uvs = true) {
    ASSERT_EQ(m.positions.size(), kPositions.size());
    for (size_t i = 0; i < kPositions.size(); ++i)
        EXPECT_TRUE(vec_near(m.positions[i], kPositions[i], 0)) << i;
    EXPECT_EQ(m.indices, kIndices);
    if (normals) {
        ASSERT_EQ(m.normals.size(), kNormals.size());
        for (size_t i = 0; i < kNormals.size(); ++i)  // renormalized floats: 1e-6
            EXPECT_TRUE(vec_near(m.normals[i], kNormals[i], 1e-6)) << i;
    }
    if (uvs) {
        ASSERT_EQ(m.uvs.size(), kUvs.size());
        for (size_t i = 0; i < kUvs.size(); ++i) {
            EXPECT_EQ(m.uvs[i].x, kUvs[i].x) << i;
            EXPECT_EQ(m.uvs[i].y, kUvs[i].y) << i;
        }
    } else {
        EXPECT_TRUE(m.uvs.empty());
    }
}

// Surface area of the pyramid: base 1 + four triangles of base 1 and slant height sqrt(1.25).
const double kPyramidArea = 1.0 + 4 * 0.5 * std::sqrt(1.25);

// -- round trips ------------------------------------------------------------------------------

TEST(PlyRoundTrip, AsciiLittleAndBigEndian) {
    ScratchDir dir;
    for (const Format f : {Format::Ascii, Format::Little, Format::Big}) {
        SCOPED_TRACE(int(f));
        auto s = load(dir.write("mesh.ply", write_ply(pyramid(), f)));
        ASSERT_TRUE(s);
        expect_pyramid(s->mesh());
        EXPECT_NEAR(s->surface_area(), kPyramidArea, kPyramidArea * 1e-6);
    }
}

TEST(PlyRoundTrip, IntegerTypesAndAlternativeNames) {
    ScratchDir dir;
    const std::vector<MeshOptions> variants = [] {
        std::vector<MeshOptions> v(5);
        v[0].count_type = "uint";
        v[0].index_type = "uint";
        v[1].count_type = "int8";
        v[1].index_type = "ushort";
        v[1].u = "s";
        v[1].v = "t";
        v[2].count_type = "ushort";
        v[2].index_type = "uint8";
        v[2].u = "texture_u";
        v[2].v = "texture_v";
        v[2].position_type = "double";
        v[3].index_type = "short";
        v[3].position_type = "float64";
        v[4].extras = false;
        return v;
    }();
    for (const MeshOptions& o : variants)
        for (const Format f : {Format::Ascii, Format::Little, Format::Big}) {
            SCOPED_TRACE(o.count_type + " " + o.index_type + " " + o.u + " " +
                         std::to_string(int(f)));
            auto s = load(dir.write("mesh.ply", write_ply(pyramid(o), f)));
            ASSERT_TRUE(s);
            expect_pyramid(s->mesh());
        }
}

TEST(PlyRoundTrip, MissingNormalsAndUvs) {
    ScratchDir dir;
    MeshOptions o;
    o.normals = false;
    o.uvs = false;
    auto s = load(dir.write("mesh.ply", write_ply(pyramid(o), Format::Little)));
    ASSERT_TRUE(s);
    expect_pyramid(s->mesh(), false, false);
    // Computed smooth normals: the apex (vertex 4) averages the four sides symmetrically,
    // so its normal is +z; every normal is unit and on the outer side of its faces.
    const TriangleMesh& m = s->mesh();
    ASSERT_EQ(m.normals.size(), 5u);
    EXPECT_TRUE(vec_near(m.normals[4], {0, 0, 1}, 1e-6));
    for (const Vec3& n : m.normals) EXPECT_NEAR(femto::length(n), 1.f, 1e-6);
    EXPECT_LT(m.normals[0].z, 0.f);  // base corner: the base (-z) dominates

    Properties flat("ply", {});
    flat.set_string("filename", dir.path("mesh.ply"));
    flat.set_bool("face_normals", true);
    auto f = make_shape(flat);
    ASSERT_TRUE(f);
    EXPECT_TRUE(f->mesh().normals.empty());
}

TEST(PlyRoundTrip, ToWorld) {
    ScratchDir dir;
    Properties props("ply", {});
    props.set_string("filename", dir.write("mesh.ply", write_ply(pyramid(), Format::Big)));
    props.set_transform("to_world", Transform::translate({1, 2, 3}) * Transform::scale({2, 2, 2}));
    auto s = make_shape(props);
    ASSERT_TRUE(s);
    for (size_t i = 0; i < kPositions.size(); ++i)
        EXPECT_TRUE(vec_near(s->mesh().positions[i], kPositions[i] * 2.f + Vec3(1, 2, 3), 0));
    EXPECT_NEAR(s->surface_area(), 4 * kPyramidArea, 4 * kPyramidArea * 1e-6);
    for (size_t i = 0; i < kNormals.size(); ++i)
        EXPECT_TRUE(vec_near(s->mesh().normals[i], kNormals[i], 1e-6));
}

// -- malformed files --------------------------------------------------------------------------

/// Loading `content` must fail with a SceneError whose message names the file and contains
/// `expected` (when given).
void expect_error(const ScratchDir& dir, const std::string& content, const std::string& expected) {
    const std::string file = dir.write("bad.ply", content);
    try {
        load(file);
        ADD_FAILURE() << "no error for:\n" << content.substr(0, 300);
    } catch (const femto::SceneError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("bad.ply"), std::string::npos) << msg;
        EXPECT_NE(msg.find(expected), std::string::npos)
            << "expected '" << expected << "' in: " << msg;
    }
}

const std::string kTriangleBody = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
std::string ascii_header(const std::string& middle) {
    return "ply\nformat ascii 1.0\n" + middle + "end_header\n";
}
const std::string kTriangleElements =
    "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\n";

TEST(PlyMalformed, Headers) {
    ScratchDir dir;
    // Sanity: the well-formed baseline loads.
    auto ok = load(dir.write("ok.ply", ascii_header(kTriangleElements) + kTriangleBody));
    ASSERT_TRUE(ok);
    EXPECT_EQ(ok->mesh().triangle_count(), 1u);

    expect_error(dir, "", "not a PLY file");
    expect_error(dir, "plx\nformat ascii 1.0\nend_header\n", "not a PLY file");
    expect_error(dir, "solid cube\nfacet normal 0 0 1\n", "not a PLY file");  // an STL file
    expect_error(dir, "ply\n" + kTriangleElements + "end_header\n" + kTriangleBody, "format");
    expect_error(dir, "ply\nformat binary_middle_endian 1.0\n" + kTriangleElements + "end_header\n",
                 "binary_middle_endian");
    expect_error(dir, "ply\nformat ascii 1.0\n" + kTriangleElements, "end_header");
    expect_error(dir, ascii_header("property float x\n" + kTriangleElements), "before any element");
    expect_error(dir,
                 ascii_header("element vertex 3\nproperty float128 x\nproperty float y\n"
                              "property float z\nelement face 1\n"
                              "property list uchar int vertex_indices\n"),
                 "float128");
    expect_error(dir,
                 ascii_header("element vertex 3\nproperty float x\nproperty float y\n"
                              "property float z\nelement face 1\n"
                              "property list float int vertex_indices\n"),
                 "integer");
    expect_error(dir,
                 ascii_header("element vertex 3\nproperty float x\nproperty float y\n"
                              "property float z\nelement face 1\n"
                              "property list uchar float vertex_indices\n"),
                 "integers");
    expect_error(dir, ascii_header("element vertex -3\n"), "count");
    expect_error(dir, ascii_header("element vertex 3x\n"), "count");
    expect_error(dir, ascii_header("elephant vertex 3\n"), "elephant");
    expect_error(dir,
                 ascii_header("element vertex 3\nproperty float x\nproperty float y\n"
                              "element face 1\nproperty list uchar int vertex_indices\n") +
                     "0 0\n1 0\n0 1\n3 0 1 2\n",
                 "x, y and z");
    expect_error(dir,
                 ascii_header("element vertex 3\nproperty float x\nproperty float y\n"
                              "property float z\nproperty float nx\n"
                              "element face 1\nproperty list uchar int vertex_indices\n"),
                 "nx, ny and nz");
    expect_error(dir,
                 ascii_header("element vertex 3\nproperty float x\nproperty float y\n"
                              "property float z\n") +
                     "0 0 0\n1 0 0\n0 1 0\n",
                 "face");
    expect_error(dir,
                 ascii_header("element vertex 3\nproperty float x\nproperty float y\n"
                              "property float z\nelement face 1\nproperty int flags\n") +
                     "0 0 0\n1 0 0\n0 1 0\n7\n",
                 "vertex_indices");
    expect_error(dir, ascii_header(kTriangleElements + "element vertex 1\n"), "twice");
}

TEST(PlyMalformed, BadData) {
    ScratchDir dir;
    const std::string header = ascii_header(kTriangleElements);
    expect_error(dir, header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "out of range");
    expect_error(dir, header + "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", "out of range");
    expect_error(dir, header + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "at least 3");
    expect_error(dir, header + "0 0 0\n1 abc 0\n0 1 0\n3 0 1 2\n", "abc");
    expect_error(dir, header + "0 0 0\n1 0 0\n0 1 nan\n3 0 1 2\n", "non-finite");
    expect_error(dir, header + "0 0 0\n1 0 0\n0 1 1e999\n3 0 1 2\n", "1e999");
    expect_error(dir, header + "0 0 0\n1 0 0\n0 1 0\n300 0 1 2\n", "uchar");  // out of type range
    expect_error(dir, header + "0 0 0\n1 0 0\n0 1 0\n3 0 1\n", "end of file");
    expect_error(dir, header + "0 0 0\n1 0 0\n", "'vertex'");
    expect_error(dir,
                 ascii_header("element vertex 3\nproperty float x\nproperty float y\n"
                              "property float z\nelement face 0\n"
                              "property list uchar int vertex_indices\n") +
                     "0 0 0\n1 0 0\n0 1 0\n",
                 "no faces");
}

TEST(PlyMalformed, AbsurdCounts) {
    ScratchDir dir;
    // Counts far beyond what the file can hold are rejected before anything is allocated.
    const std::string big_vertex =
        "element vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\n";
    expect_error(dir, ascii_header(big_vertex) + kTriangleBody, "4000000000");
    expect_error(dir,
                 "ply\nformat binary_little_endian 1.0\n" + big_vertex + "end_header\n" +
                     std::string(64, '\0'),
                 "4000000000");
    expect_error(dir,
                 "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\n"
                 "property float y\nproperty float z\nelement face 18446744073709551615\n"
                 "property list uchar int vertex_indices\nend_header\n" +
                     std::string(36 + 13, '\0'),
                 "18446744073709551615");
    expect_error(dir, ascii_header("element vertex 99999999999999999999999\n"), "count");
    // An element without properties takes no bytes, whatever its count: skipped at once.
    {
        const std::string file =
            dir.write("empty_elem.ply",
                      ascii_header("element nothing 18446744073709551615\n" + kTriangleElements) +
                          kTriangleBody);
        auto s = load(file);
        ASSERT_TRUE(s);
        EXPECT_EQ(s->mesh().triangle_count(), 1u);
    }
    // A list length of 2^32 - 1 in a small binary file.
    std::string data =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nelement face 1\n"
        "property list uint int vertex_indices\nend_header\n";
    for (int i = 0; i < 9; ++i) put<float>(data, i == 3 || i == 7 ? 1.0 : 0.0, false);
    put<uint32_t>(data, 4294967295.0, false);
    for (int i = 0; i < 3; ++i) put<int32_t>(data, i, false);
    expect_error(dir, data, "4294967295");
    // Same in an unknown element's list, which is skipped rather than read.
    std::string skip =
        "ply\nformat binary_big_endian 1.0\nelement junk 1\n"
        "property list uint double stuff\n" +
        kTriangleElements + "end_header\n";
    put<uint32_t>(skip, 4294967295.0, true);
    expect_error(dir, skip + std::string(64, '\0'), "4294967295");
}

TEST(PlyMalformed, EveryTruncationOfABinaryFileIsAnError) {
    ScratchDir dir;
    for (const Format f : {Format::Little, Format::Big}) {
        const std::string full = write_ply(pyramid(), f);
        ASSERT_TRUE(load(dir.write("full.ply", full)));
        // Every byte of this file is read (no trailing padding), so each proper prefix is a
        // truncated file.
        for (size_t len = 0; len < full.size(); ++len) {
            const std::string file = dir.write("cut.ply", full.substr(0, len));
            EXPECT_THROW(load(file), femto::SceneError) << "prefix of " << len << " bytes";
        }
    }
}

TEST(PlyMalformed, RandomCorruptionNeverCrashes) {
    // Random byte changes in the header and data: loading either succeeds (the change hit a
    // skipped property, or made another valid file) or is a SceneError. Anything else (a
    // crash, another exception type) fails the test.
    ScratchDir dir;
    std::mt19937 rng(1234);
    int errors = 0, loaded = 0;
    for (const Format f : {Format::Ascii, Format::Little, Format::Big}) {
        const std::string full = write_ply(pyramid(), f);
        for (int iter = 0; iter < 300; ++iter) {
            std::string bad = full;
            const int changes = 1 + int(rng() % 4);
            for (int c = 0; c < changes; ++c) {
                const size_t pos = rng() % bad.size();
                switch (rng() % 3) {
                    case 0:
                        bad[pos] = char(rng() & 0xff);
                        break;
                    case 1:
                        bad[pos] = char("0123456789 \n-.e"[rng() % 15]);
                        break;
                    default:
                        bad.erase(pos, 1 + rng() % 8);
                        break;
                }
                if (bad.empty()) bad = "p";
            }
            const std::string file = dir.write("fuzz.ply", bad);
            try {
                load(file);
                ++loaded;
            } catch (const femto::SceneError&) {
                ++errors;
            } catch (const std::exception& e) {
                ADD_FAILURE() << "unexpected exception: " << e.what();
            }
        }
    }
    EXPECT_GT(errors, 0);
    EXPECT_EQ(errors + loaded, 900);
}

TEST(PlyMalformed, MissingFileAndDirectory) {
    ScratchDir dir;
    Properties props("ply", {});
    props.set_string("filename", dir.path("nope.ply"));
    try {
        make_shape(props);
        ADD_FAILURE() << "no error";
    } catch (const femto::SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("nope.ply"), std::string::npos) << e.what();
    }
    Properties d("ply", {});
    d.set_string("filename", dir.path(""));
    EXPECT_THROW(make_shape(d), femto::SceneError);
}

}  // namespace
