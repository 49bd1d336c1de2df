// ply: Stanford PLY triangle meshes, with a reader of our own.
//
// Debian has no PLY library (no rply, happly or tinyply package; assimp reads PLY but is a
// large dependency for one format), so this file reads PLY itself: the ascii,
// binary_little_endian and binary_big_endian formats; a `vertex` element with x y z,
// optional nx ny nz and optional texture coordinates (u v, s t, texture_u texture_v or
// texture_s texture_t) of any scalar type; a `face` element whose `vertex_indices` (or
// `vertex_index`) list has any integer count and index types, polygons triangulated as a
// fan. Any other element or property (colours, confidence, materials, edges, ...) is
// skipped, lists included.
//
// The file is untrusted input: every read is bounds-checked, every element count and list
// length is checked against the bytes left in the file before anything is allocated or
// looped over, and every index against the vertex count. Bad input is a SceneError naming
// the file and the element/item where reading failed, never a crash.
//
// Conventions follow Mitsuba's ply plugin (no v flip; vertex normals used unless
// face_normals; missing normals computed as smooth angle-weighted vertex normals).
#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "femto/input_file.h"
#include "femto/plugin.h"
#include "femto/shape.h"
#include "femto/transform.h"

namespace femto {
namespace {

// -- the PLY format ---------------------------------------------------------------------------

enum class PlyType : uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
enum class PlyFormat : uint8_t { Ascii, BinaryLittleEndian, BinaryBigEndian };

struct PlyTypeInfo {
    const char* name;
    const char* alias;
    PlyType type;
    size_t size;
    double min, max;  ///< representable range (integers only)
};
constexpr PlyTypeInfo kTypes[] = {
    {"char", "int8", PlyType::Int8, 1, -128.0, 127.0},
    {"uchar", "uint8", PlyType::UInt8, 1, 0.0, 255.0},
    {"short", "int16", PlyType::Int16, 2, -32768.0, 32767.0},
    {"ushort", "uint16", PlyType::UInt16, 2, 0.0, 65535.0},
    {"int", "int32", PlyType::Int32, 4, -2147483648.0, 2147483647.0},
    {"uint", "uint32", PlyType::UInt32, 4, 0.0, 4294967295.0},
    {"float", "float32", PlyType::Float32, 4, 0.0, 0.0},
    {"double", "float64", PlyType::Float64, 8, 0.0, 0.0},
};
const PlyTypeInfo& info(PlyType t) { return kTypes[static_cast<int>(t)]; }
bool is_integer(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

struct PlyProperty {
    std::string name;
    PlyType type = PlyType::Float32;  ///< value type (list entries for lists)
    bool is_list = false;
    PlyType count_type = PlyType::UInt8;
};

struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> props;
};

std::string shorten(std::string_view s) {
    return s.size() <= 40 ? std::string(s) : std::string(s.substr(0, 40)) + "...";
}

bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

std::vector<std::string_view> split(std::string_view line) {
    std::vector<std::string_view> out;
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && is_space(line[i])) ++i;
        const size_t start = i;
        while (i < line.size() && !is_space(line[i])) ++i;
        if (i > start) out.push_back(line.substr(start, i - start));
    }
    return out;
}

class PlyReader {
public:
    PlyReader(const Properties& props, std::string filename)
        : props_(props), filename_(std::move(filename)) {}

    TriangleMesh read() {
        load_file();
        parse_header();
        return read_body();
    }

private:
    [[noreturn]] void fail(const std::string& message) const {
        props_.fail("filename", "\"" + filename_ + "\": " + message);
    }
    /// A failure while reading element data: says which item it happened in.
    [[noreturn]] void data_fail(const std::string& message) const {
        std::string where;
        if (element_)
            where = " (in '" + element_->name + "' " + std::to_string(item_) + " (0-based) of " +
                    std::to_string(element_->count) + ", at byte " + std::to_string(pos_) + ")";
        fail(message + where);
    }

    void load_file() {
        InputFile file(filename_, props_.location_of("filename"));
        data_.resize(static_cast<size_t>(file.size()));
        data_.resize(file.read(data_.data(), data_.size()));
    }

    // -- header ------------------------------------------------------------------------------

    bool parse_type(std::string_view name, PlyType& t) const {
        for (const auto& ti : kTypes)
            if (name == ti.name || name == ti.alias) {
                t = ti.type;
                return true;
            }
        return false;
    }

    void parse_header() {
        size_t pos = 0;
        auto next_line = [&](std::string_view& line) {
            if (pos >= data_.size()) return false;
            const char* begin = data_.data() + pos;
            const void* nl = std::memchr(begin, '\n', data_.size() - pos);
            const size_t len =
                nl ? static_cast<size_t>(static_cast<const char*>(nl) - begin) : data_.size() - pos;
            line = std::string_view(begin, len);
            pos += len + (nl ? 1 : 0);
            return true;
        };
        std::string_view line;
        if (!next_line(line) || split(line).size() != 1 || split(line)[0] != "ply")
            fail("not a PLY file (the first line must be \"ply\")");
        bool have_format = false, done = false;
        int line_no = 1;
        while (!done && next_line(line)) {
            ++line_no;
            const auto tok = split(line);
            if (tok.empty()) continue;
            const std::string where = "header line " + std::to_string(line_no) + ": ";
            if (tok[0] == "comment" || tok[0] == "obj_info") continue;
            if (tok[0] == "format") {
                if (tok.size() != 3) fail(where + "expected \"format <type> 1.0\"");
                if (tok[1] == "ascii")
                    format_ = PlyFormat::Ascii;
                else if (tok[1] == "binary_little_endian")
                    format_ = PlyFormat::BinaryLittleEndian;
                else if (tok[1] == "binary_big_endian")
                    format_ = PlyFormat::BinaryBigEndian;
                else
                    fail(where + "unknown format '" + shorten(tok[1]) +
                         "' (valid: ascii, binary_little_endian, binary_big_endian)");
                have_format = true;
            } else if (tok[0] == "element") {
                if (tok.size() != 3) fail(where + "expected \"element <name> <count>\"");
                PlyElement e;
                e.name = std::string(tok[1]);
                const auto [end, ec] =
                    std::from_chars(tok[2].data(), tok[2].data() + tok[2].size(), e.count);
                if (ec != std::errc() || end != tok[2].data() + tok[2].size())
                    fail(where + "invalid count '" + shorten(tok[2]) + "' of element '" + e.name +
                         "' (a non-negative integer is expected)");
                for (const auto& other : elements_)
                    if (other.name == e.name)
                        fail(where + "element '" + e.name + "' appears twice");
                elements_.push_back(std::move(e));
            } else if (tok[0] == "property") {
                if (elements_.empty()) fail(where + "a property before any element");
                PlyProperty p;
                if (tok.size() == 5 && tok[1] == "list") {
                    p.is_list = true;
                    if (!parse_type(tok[2], p.count_type))
                        fail(where + "unknown type '" + shorten(tok[2]) + "'");
                    if (!is_integer(p.count_type))
                        fail(where + "the length type of a list must be an integer type, not '" +
                             std::string(tok[2]) + "'");
                    if (!parse_type(tok[3], p.type))
                        fail(where + "unknown type '" + shorten(tok[3]) + "'");
                    p.name = std::string(tok[4]);
                } else if (tok.size() == 3 && tok[1] != "list") {
                    if (!parse_type(tok[1], p.type))
                        fail(where + "unknown type '" + shorten(tok[1]) +
                             "' (valid: char uchar short ushort int uint float double, or "
                             "int8 ... float64)");
                    p.name = std::string(tok[2]);
                } else {
                    fail(where +
                         "expected \"property <type> <name>\" or \"property list "
                         "<count type> <type> <name>\"");
                }
                elements_.back().props.push_back(std::move(p));
            } else if (tok[0] == "end_header") {
                done = true;
            } else {
                fail(where + "unknown header keyword '" + shorten(tok[0]) +
                     "' (valid: format, element, property, comment, obj_info, end_header)");
            }
        }
        if (!done) fail("the header has no end_header line (truncated file?)");
        if (!have_format) fail("the header has no format line");
        pos_ = pos;
        swap_bytes_ =
            (format_ == PlyFormat::BinaryBigEndian) != (std::endian::native == std::endian::big);
    }

    // -- values ------------------------------------------------------------------------------

    size_t remaining() const { return data_.size() - pos_; }

    double read_binary(PlyType t) {
        const size_t n = info(t).size;
        if (remaining() < n) data_fail("unexpected end of file");
        unsigned char b[8];
        std::memcpy(b, data_.data() + pos_, n);
        pos_ += n;
        if (swap_bytes_) std::reverse(b, b + n);
        switch (t) {
            case PlyType::Int8:
                return static_cast<int8_t>(b[0]);
            case PlyType::UInt8:
                return b[0];
            case PlyType::Int16:
                return load<int16_t>(b);
            case PlyType::UInt16:
                return load<uint16_t>(b);
            case PlyType::Int32:
                return load<int32_t>(b);
            case PlyType::UInt32:
                return load<uint32_t>(b);
            case PlyType::Float32:
                return load<float>(b);
            case PlyType::Float64:
                return load<double>(b);
        }
        return 0;
    }
    template <typename T>
    static double load(const unsigned char* b) {
        T v;
        std::memcpy(&v, b, sizeof(T));
        return static_cast<double>(v);
    }

    std::string_view next_token() {
        while (pos_ < data_.size() && is_space(data_[pos_])) ++pos_;
        if (pos_ >= data_.size()) data_fail("unexpected end of file");
        const size_t start = pos_;
        while (pos_ < data_.size() && !is_space(data_[pos_])) ++pos_;
        return std::string_view(data_.data() + start, pos_ - start);
    }

    double read_ascii(PlyType t) {
        const std::string_view tok = next_token();
        const char* b = tok.data();
        const char* e = tok.data() + tok.size();
        if (b != e && *b == '+') ++b;  // from_chars does not take a leading '+'
        // std::from_chars: locale-independent, never reads past the token.
        double v = 0;
        if (is_integer(t)) {
            int64_t i = 0;
            const auto [end, ec] = std::from_chars(b, e, i);
            if (ec == std::errc() && end == e) {
                v = static_cast<double>(i);
            } else {  // some writers print integers as "3.0"
                const auto [end2, ec2] = std::from_chars(b, e, v);
                if (ec2 != std::errc() || end2 != e || v != std::floor(v))
                    data_fail("invalid " + std::string(info(t).name) + " value '" + shorten(tok) +
                              "'");
            }
            if (v < info(t).min || v > info(t).max)
                data_fail("value " + shorten(tok) + " out of the range of type " + info(t).name);
        } else {
            const auto [end, ec] = std::from_chars(b, e, v);
            if (ec == std::errc::result_out_of_range)
                data_fail("number '" + shorten(tok) + "' out of range");
            if (ec != std::errc() || end != e) data_fail("invalid number '" + shorten(tok) + "'");
        }
        return v;
    }

    double read_value(PlyType t) {
        return format_ == PlyFormat::Ascii ? read_ascii(t) : read_binary(t);
    }

    /// Reads a list length and checks that the list fits in the rest of the file.
    uint64_t read_list_length(const PlyProperty& p) {
        const double n = read_value(p.count_type);
        if (n < 0) data_fail("negative list length " + std::to_string(static_cast<int64_t>(n)));
        const uint64_t count = static_cast<uint64_t>(n);
        // Binary entries take their size in bytes; ascii ones at least one character and a
        // separator (the last one possibly without).
        const uint64_t capacity =
            format_ == PlyFormat::Ascii ? remaining() / 2 + 1 : remaining() / info(p.type).size;
        if (count > capacity)
            data_fail("list '" + p.name + "' of " + std::to_string(count) +
                      " entries runs past the end of the file (truncated or corrupt file)");
        return count;
    }

    void skip(const PlyProperty& p) {
        if (!p.is_list) {
            read_value(p.type);
            return;
        }
        const uint64_t n = read_list_length(p);
        if (format_ == PlyFormat::Ascii) {
            for (uint64_t i = 0; i < n; ++i) read_ascii(p.type);
        } else {
            pos_ += static_cast<size_t>(n) * info(p.type).size;  // fits: checked above
        }
    }

    /// Rejects an element count the rest of the file cannot hold, before looping over it.
    /// Returns false for elements without properties (nothing to read, whatever the count).
    bool check_fits(const PlyElement& e) {
        if (e.props.empty() || e.count == 0) return false;
        uint64_t capacity = 0;
        if (format_ == PlyFormat::Ascii) {
            // Every value takes at least one character plus a separator.
            capacity = (remaining() / 2 + 1) / e.props.size();
        } else {
            size_t min_size = 0;  // a list takes at least its length field
            for (const auto& p : e.props) min_size += info(p.is_list ? p.count_type : p.type).size;
            capacity = remaining() / min_size;
        }
        if (e.count > capacity)
            fail("the header declares " + std::to_string(e.count) + " '" + e.name +
                 "' elements, more than the remaining " + std::to_string(remaining()) +
                 " bytes of the file can hold (truncated or corrupt file)");
        return true;
    }

    // -- body --------------------------------------------------------------------------------

    TriangleMesh read_body() {
        enum Slot { X, Y, Z, NX, NY, NZ, U, V, kSlots };
        const PlyElement* vertex_elem = nullptr;
        const PlyElement* face_elem = nullptr;
        for (const auto& e : elements_) {
            if (e.name == "vertex") vertex_elem = &e;
            if (e.name == "face") face_elem = &e;
        }
        if (!vertex_elem) fail("no 'vertex' element in the header");
        if (!face_elem)
            fail(
                "no 'face' element in the header (point clouds cannot be rendered as a "
                "surface)");
        if (vertex_elem->count > UINT32_MAX)
            fail("more than 2^32 - 1 vertices (" + std::to_string(vertex_elem->count) + ")");
        const uint64_t vertex_count = vertex_elem->count;

        // Map vertex properties to slots.
        std::vector<int> slot_of(vertex_elem->props.size(), -1);
        bool have[kSlots] = {};
        auto assign = [](std::string_view n) -> int {
            if (n == "x") return X;
            if (n == "y") return Y;
            if (n == "z") return Z;
            if (n == "nx") return NX;
            if (n == "ny") return NY;
            if (n == "nz") return NZ;
            if (n == "u" || n == "s" || n == "texture_u" || n == "texture_s") return U;
            if (n == "v" || n == "t" || n == "texture_v" || n == "texture_t") return V;
            return -1;
        };
        for (size_t i = 0; i < vertex_elem->props.size(); ++i) {
            const PlyProperty& p = vertex_elem->props[i];
            const int s = assign(p.name);
            if (s < 0) continue;
            if (p.is_list) fail("vertex property '" + p.name + "' must be a scalar, not a list");
            if (have[s]) fail("vertex property '" + p.name + "' is given twice");
            have[s] = true;
            slot_of[i] = s;
        }
        if (!have[X] || !have[Y] || !have[Z])
            fail("the vertex element needs the properties x, y and z");
        const bool normals = have[NX] || have[NY] || have[NZ];
        if (normals && !(have[NX] && have[NY] && have[NZ]))
            fail("vertex normals need all three properties nx, ny and nz");
        const bool uvs = have[U] || have[V];
        if (uvs && !(have[U] && have[V]))
            fail("texture coordinates need both properties u and v (or s and t)");

        int index_prop = -1;
        for (size_t i = 0; i < face_elem->props.size(); ++i) {
            const PlyProperty& p = face_elem->props[i];
            if (p.name == "vertex_indices" || p.name == "vertex_index") {
                if (!p.is_list) fail("face property '" + p.name + "' must be a list");
                if (!is_integer(p.type))
                    fail("face property '" + p.name + "' must hold integers, not " +
                         info(p.type).name);
                index_prop = static_cast<int>(i);
            }
        }
        if (index_prop < 0) fail("the face element has no 'vertex_indices' list");

        TriangleMesh mesh;
        std::vector<uint32_t> polygon;
        for (const PlyElement& e : elements_) {
            element_ = &e;
            item_ = 0;
            if (!check_fits(e)) continue;
            if (&e == vertex_elem) {
                mesh.positions.reserve(e.count);
                if (normals) mesh.normals.reserve(e.count);
                if (uvs) mesh.uvs.reserve(e.count);
                double val[kSlots] = {};
                for (item_ = 0; item_ < e.count; ++item_) {
                    for (size_t i = 0; i < e.props.size(); ++i) {
                        if (slot_of[i] < 0)
                            skip(e.props[i]);
                        else
                            val[slot_of[i]] = read_value(e.props[i].type);
                    }
                    const Vec3 p{static_cast<float>(val[X]), static_cast<float>(val[Y]),
                                 static_cast<float>(val[Z])};
                    if (!is_finite(p)) data_fail("non-finite vertex position");
                    mesh.positions.push_back(p);
                    if (normals)
                        mesh.normals.push_back({static_cast<float>(val[NX]),
                                                static_cast<float>(val[NY]),
                                                static_cast<float>(val[NZ])});
                    if (uvs) {
                        const Vec2 uv{static_cast<float>(val[U]), static_cast<float>(val[V])};
                        if (!std::isfinite(uv.x) || !std::isfinite(uv.y))
                            data_fail("non-finite texture coordinate");
                        mesh.uvs.push_back(uv);
                    }
                }
            } else if (&e == face_elem) {
                for (item_ = 0; item_ < e.count; ++item_) {
                    for (size_t i = 0; i < e.props.size(); ++i) {
                        const PlyProperty& p = e.props[i];
                        if (static_cast<int>(i) != index_prop) {
                            skip(p);
                            continue;
                        }
                        const uint64_t n = read_list_length(p);
                        if (n < 3)
                            data_fail("a face with " + std::to_string(n) +
                                      " vertices (at least 3 are needed)");
                        polygon.clear();
                        for (uint64_t k = 0; k < n; ++k) {
                            const double idx = read_value(p.type);
                            if (idx < 0 || idx >= static_cast<double>(vertex_count))
                                data_fail("vertex index " +
                                          std::to_string(static_cast<int64_t>(idx)) +
                                          " out of range (the file has " +
                                          std::to_string(vertex_count) + " vertices)");
                            polygon.push_back(static_cast<uint32_t>(idx));
                        }
                        for (size_t k = 1; k + 1 < polygon.size(); ++k) {
                            mesh.indices.push_back(polygon[0]);
                            mesh.indices.push_back(polygon[k]);
                            mesh.indices.push_back(polygon[k + 1]);
                        }
                    }
                }
            } else {
                for (item_ = 0; item_ < e.count; ++item_)
                    for (const auto& p : e.props) skip(p);
            }
        }
        element_ = nullptr;
        if (mesh.indices.empty()) fail("the mesh has no faces");
        return mesh;
    }

    const Properties& props_;
    std::string filename_;
    std::vector<char> data_;
    size_t pos_ = 0;
    PlyFormat format_ = PlyFormat::Ascii;
    bool swap_bytes_ = false;
    std::vector<PlyElement> elements_;
    const PlyElement* element_ = nullptr;  ///< being read (for error messages)
    uint64_t item_ = 0;
};

class PlyShape final : public Shape {
public:
    explicit PlyShape(const Properties& props) : Shape(props) {
        const std::string filename = props.get_string("filename");
        const bool face_normals = props.get_bool("face_normals", false);
        const Transform& to_world = to_world_;

        TriangleMesh mesh = PlyReader(props, filename).read();
        mesh_to_world(mesh, to_world, face_normals);
        set_mesh(std::move(mesh));
    }
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::PlyShape, femto::PluginKind::Shape, "ply",
             "Stanford PLY triangle mesh (ascii and binary; polygons triangulated)",
             {{"filename", "filename", "", "path of the .ply file (relative to the scene file)"},
              {"face_normals", "boolean", "false",
               "ignore vertex normals and shade with the flat face normals"}})
