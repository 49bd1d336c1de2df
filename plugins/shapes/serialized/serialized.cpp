// serialized: Mitsuba's compressed triangle-mesh format (.serialized), read with zlib.
//
// The format (Mitsuba 0.6 and 3, little endian): per mesh a header (uint16 0x041C, uint16
// version 3 or 4) and a zlib stream holding uint32 flags (0x1 normals, 0x2 texture
// coordinates, 0x8 colours, 0x10 face normals, 0x2000 double precision), in version 4 the
// mesh's name (a NUL-terminated string), uint64 vertex and triangle counts, then positions,
// normals, uvs, colours (each present as the flags say) and the triangles' uint32 indices
// (uint64 beyond 2^32 vertices, which femto refuses). A file holding several meshes
// concatenates them and ends with each mesh's byte offset (uint64, or uint32 in version 3)
// and their count (uint32); `shape_index` picks one. Colours are read past (femto's meshes
// have none), as Mitsuba 3 does.
//
// The file is untrusted input: the counts are checked against what the compressed bytes
// can hold (zlib expands at most ~1032:1) before anything is allocated, every index against
// the vertex count, and a stream that ends early or is corrupt is a located error naming the
// file and what was being read.
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <string>
#include <vector>

#include "femto/input_file.h"
#include "femto/plugin.h"
#include "femto/shape.h"
#include "femto/transform.h"

namespace femto {
namespace {

constexpr uint16_t kMagic = 0x041C;
constexpr uint32_t kHasNormals = 0x0001, kHasUvs = 0x0002, kHasColours = 0x0008,
                   kFaceNormals = 0x0010, kDoublePrecision = 0x2000;
// zlib's DEFLATE expands one compressed byte into at most ~1032 bytes.
constexpr uint64_t kMaxExpansion = 1100;

// Reads the decompressed stream of one mesh, starting at byte `offset` of `data`.
class MeshStream {
public:
    MeshStream(const std::string& data, size_t offset, const Properties& props,
               const std::string& filename)
        : props_(props), filename_(filename), compressed_(data.size() - offset) {
        zs_.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data() + offset));
        zs_.avail_in = static_cast<uInt>(std::min<size_t>(compressed_, UINT32_MAX));
        if (inflateInit(&zs_) != Z_OK) fail("zlib could not start decompressing");
        open_ = true;
    }
    ~MeshStream() {
        if (open_) inflateEnd(&zs_);
    }
    MeshStream(const MeshStream&) = delete;
    MeshStream& operator=(const MeshStream&) = delete;

    [[noreturn]] void fail(const std::string& message) const {
        props_.fail("filename", "\"" + filename_ + "\": " + message);
    }

    /// Fills `out` with `count` bytes of the stream; `what` names them for errors.
    void read(void* out, size_t count, const char* what) {
        zs_.next_out = static_cast<Bytef*>(out);
        while (count > 0) {
            const uInt chunk = static_cast<uInt>(std::min<size_t>(count, 1u << 30));
            zs_.avail_out = chunk;
            const int rc = inflate(&zs_, Z_NO_FLUSH);
            count -= chunk - zs_.avail_out;
            if (count == 0) break;
            if (rc == Z_STREAM_END || (rc == Z_BUF_ERROR && zs_.avail_in == 0))
                fail(std::string("the mesh data ends before its ") + what);
            if (rc != Z_OK)
                fail(std::string("corrupt compressed data in the ") + what +
                     " (zlib: " + (zs_.msg ? zs_.msg : "error " + std::to_string(rc)) + ")");
        }
    }
    template <typename T>
    T value(const char* what) {
        T v{};
        read(&v, sizeof v, what);
        return v;
    }
    /// `count` values of type T. Read in pieces, so that memory grows only as fast as data
    /// actually decompresses (a corrupt count fails at the end of the data, not in malloc).
    template <typename T>
    std::vector<T> array(uint64_t count, const char* what) {
        constexpr uint64_t kPiece = (uint64_t(4) << 20) / sizeof(T);
        std::vector<T> out;
        for (uint64_t done = 0; done < count;) {
            const uint64_t n = std::min(kPiece, count - done);
            out.resize(done + n);
            read(out.data() + done, n * sizeof(T), what);
            done += n;
        }
        return out;
    }
    /// `count` numbers stored as float or double, as floats.
    std::vector<float> floats(uint64_t count, bool double_precision, const char* what) {
        if (!double_precision) return array<float>(count, what);
        const std::vector<double> wide = array<double>(count, what);
        return std::vector<float>(wide.begin(), wide.end());
    }
    /// Checks that the stream ends here, its checksum included (zlib verifies it): a file cut
    /// short or altered in its last bytes is refused, not read as a mesh that looks whole.
    void finish() {
        unsigned char extra = 0;
        zs_.next_out = &extra;
        zs_.avail_out = 1;
        const int rc = inflate(&zs_, Z_FINISH);
        if (rc == Z_STREAM_END && zs_.avail_out == 1) return;
        if (zs_.avail_out == 0) fail("the mesh data goes on past its triangles");
        if (zs_.avail_in == 0) fail("the compressed data ends before its checksum");
        fail(std::string("corrupt compressed data at its end (zlib: ") +
             (zs_.msg ? zs_.msg : "error " + std::to_string(rc)) + ")");
    }
    /// Whether `bytes` of decompressed data could come from the compressed bytes at all.
    bool plausible(uint64_t bytes) const { return bytes / kMaxExpansion <= compressed_; }

private:
    const Properties& props_;
    const std::string& filename_;
    size_t compressed_;
    z_stream zs_{};
    bool open_ = false;
};

class SerializedReader {
public:
    SerializedReader(const Properties& props, std::string filename)
        : props_(props), filename_(std::move(filename)) {}

    /// Reads mesh `index`; `face_normals` is set when the file asks for flat shading.
    TriangleMesh read(int64_t index, bool& face_normals) {
        InputFile file(filename_, props_.location_of("filename"));
        data_.resize(static_cast<size_t>(file.size()));
        data_.resize(file.read(data_.data(), data_.size()));
        const size_t offset = mesh_offset(index);
        MeshStream stream(data_, offset + 4, props_, filename_);
        const uint32_t flags = stream.value<uint32_t>("flags");
        if (version_ >= 4) skip_name(stream);
        face_normals = (flags & kFaceNormals) != 0;
        return read_mesh(stream, flags);
    }

private:
    [[noreturn]] void fail(const std::string& message) const {
        props_.fail("filename", "\"" + filename_ + "\": " + message);
    }
    template <typename T>
    T at(size_t pos) const {
        T v;
        std::memcpy(&v, data_.data() + pos, sizeof v);
        return v;
    }

    // Where mesh `index` starts: 0 for the first; the end-of-file dictionary for the others.
    size_t mesh_offset(int64_t index) {
        read_header(0);
        if (index == 0) return 0;
        if (data_.size() < 8) fail("too short to hold a dictionary of meshes");
        const uint32_t count = at<uint32_t>(data_.size() - 4);
        if (uint64_t(index) >= count)
            fail("shape_index " + std::to_string(index) + " is out of range: the file holds " +
                 std::to_string(count) + " mesh(es)");
        const size_t entry = version_ >= 4 ? 8 : 4;
        if (uint64_t(count) * entry + 4 > data_.size())
            fail("its dictionary of " + std::to_string(count) + " meshes does not fit in the file");
        const size_t pos = data_.size() - 4 - size_t(count - index) * entry;
        const uint64_t offset = entry == 8 ? at<uint64_t>(pos) : at<uint32_t>(pos);
        if (offset + 4 > data_.size())
            fail("mesh " + std::to_string(index) + " starts at byte " + std::to_string(offset) +
                 ", past the end of the file");
        read_header(size_t(offset));
        return size_t(offset);
    }

    void read_header(size_t pos) {
        if (pos + 4 > data_.size()) fail("too short to be a serialized mesh");
        if (at<uint16_t>(pos) != kMagic)
            fail("not a Mitsuba serialized mesh (no 0x041C header at byte " + std::to_string(pos) +
                 ")");
        const uint16_t version = at<uint16_t>(pos + 2);
        if (version != 3 && version != 4)
            fail("file version " + std::to_string(version) + " is not 3 or 4");
        version_ = version;
    }

    static void skip_name(MeshStream& stream) {
        for (size_t n = 0;; ++n) {
            if (n > 65536) stream.fail("the mesh's name is not terminated");
            if (stream.value<char>("name") == '\0') return;
        }
    }

    TriangleMesh read_mesh(MeshStream& stream, uint32_t flags) {
        const uint64_t vertices = stream.value<uint64_t>("vertex count");
        const uint64_t triangles = stream.value<uint64_t>("triangle count");
        const bool wide = (flags & kDoublePrecision) != 0;
        const uint64_t scalar = wide ? 8 : 4;
        if (vertices > UINT32_MAX)
            fail(std::to_string(vertices) + " vertices: femto's meshes hold at most 2^32");
        // Both counts are bounded by 2^32 (triangles by the check below), so no overflow.
        if (triangles > UINT32_MAX || !stream.plausible(vertices * 3 * scalar + triangles * 12))
            fail(std::to_string(vertices) + " vertices and " + std::to_string(triangles) +
                 " triangles cannot come from " + std::to_string(data_.size()) +
                 " bytes of compressed data (a corrupt header?)");
        TriangleMesh mesh;
        mesh.positions = to_vec3(stream.floats(vertices * 3, wide, "positions"));
        if (flags & kHasNormals)
            mesh.normals = to_vec3(stream.floats(vertices * 3, wide, "normals"));
        if (flags & kHasUvs) mesh.uvs = to_vec2(stream.floats(vertices * 2, wide, "uvs"));
        if (flags & kHasColours) stream.floats(vertices * 3, wide, "colours");
        mesh.indices = stream.array<uint32_t>(triangles * 3, "triangles");
        stream.finish();
        for (size_t i = 0; i < mesh.indices.size(); ++i)
            if (mesh.indices[i] >= vertices)
                fail("triangle " + std::to_string(i / 3) + " (0-based) uses vertex " +
                     std::to_string(mesh.indices[i]) + " of " + std::to_string(vertices));
        return mesh;
    }

    static std::vector<Vec3> to_vec3(const std::vector<float>& v) {
        std::vector<Vec3> out(v.size() / 3);
        for (size_t i = 0; i < out.size(); ++i) out[i] = Vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
        return out;
    }
    static std::vector<Vec2> to_vec2(const std::vector<float>& v) {
        std::vector<Vec2> out(v.size() / 2);
        for (size_t i = 0; i < out.size(); ++i) out[i] = Vec2(v[2 * i], v[2 * i + 1]);
        return out;
    }

    const Properties& props_;
    std::string filename_;
    std::string data_;
    uint16_t version_ = 4;
};

class SerializedShape final : public Shape {
public:
    explicit SerializedShape(const Properties& props) : Shape(props) {
        const int64_t index = props.get_int("shape_index", 0);
        if (index < 0) props.fail("shape_index", "shape_index must be >= 0");
        bool file_face_normals = false;
        TriangleMesh mesh =
            SerializedReader(props, props.get_string("filename")).read(index, file_face_normals);
        const bool face_normals = props.get_bool("face_normals", false) || file_face_normals;
        mesh_to_world(mesh, to_world_, face_normals);
        set_mesh(std::move(mesh));
    }
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::SerializedShape, femto::PluginKind::Shape, "serialized",
             "Mitsuba's compressed triangle mesh (.serialized, versions 3 and 4)",
             {{"filename", "filename", "",
               "path of the .serialized file (relative to the scene file)"},
              {"shape_index", "integer", "0", "which mesh of a file holding several (0-based)"},
              {"face_normals", "boolean", "false",
               "ignore vertex normals and shade with the flat face normals"}})
