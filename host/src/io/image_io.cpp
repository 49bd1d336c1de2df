#include "femto/image_io.h"

#include <OpenColorIO/OpenColorIO.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfDoubleAttribute.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <dlfcn.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <png.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>

#include "femto/color.h"
#include "femto/error.h"
#include "femto/input_file.h"
#include "femto/memory.h"
#include "io/atomic_file.h"
#include "io/display.h"
#include "io/exr_png.h"
#include "io/oiio_module.h"

namespace fs = std::filesystem;
namespace OCIO = OCIO_NAMESPACE;

namespace femto::io {

namespace detail {

struct OutputSetAccess {
    static std::vector<OutputSet*>& open_sets();
    static bool hold(const std::string& tmp, const std::string& path);
};

std::string temp_path_for(const std::string& path) {
    static std::atomic<unsigned> counter{0};
    const fs::path p(path);
    return (p.parent_path() / fmt::format(".{}.tmp{}-{}{}", p.stem().string(), getpid(), counter++,
                                          p.extension().string()))
        .string();
}

void commit_file(const std::string& tmp, const std::string& path) {
    if (OutputSetAccess::hold(tmp, path)) return;  // renamed with the rest of its set
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        std::error_code ignored;  // the rename's reason is the one to report
        fs::remove(tmp, ignored);
        throw SceneError(fmt::format("cannot write \"{}\": {}", path, ec.message()));
    }
}

OCIO::ConstCPUProcessorRcPtr display_processor() {
    static std::once_flag once;
    static OCIO::ConstCPUProcessorRcPtr processor;
    static std::string error;
    std::call_once(once, [] {
        try {
            auto config = OCIO::Config::CreateFromFile(ocio_config_path().c_str());
            processor = config->getProcessor("linear", "sRGB")->getDefaultCPUProcessor();
        } catch (const std::exception& e) {
            error = e.what();
        }
    });
    if (!processor)
        throw std::runtime_error(
            fmt::format("OpenColorIO config {}: {}", ocio_config_path(), error));
    return processor;
}

const OiioModule& oiio_module() {
    static std::once_flag once;
    static const OiioModule* module = nullptr;
    static std::string error;
    std::call_once(once, [] {
        // Beside libfemto_io, in the build tree and where it is installed: next to the file
        // itself (through a symlinked libfemto_io, too), else next to the name it was loaded by.
        const fs::path name = "libfemto_oiio.so";
        std::vector<fs::path> candidates;
        Dl_info info{};
        if (dladdr(reinterpret_cast<void*>(&oiio_module), &info) && info.dli_fname) {
            std::error_code ec;
            if (const fs::path real = fs::canonical(info.dli_fname, ec); !ec)
                candidates.push_back(real.parent_path() / name);
            candidates.push_back(fs::path(info.dli_fname).parent_path() / name);
        }
        // Not by its bare name: the loader would search LD_LIBRARY_PATH and the system's
        // folders, and a module must come from femto's own installation.
        candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
        void* handle = nullptr;
        fs::path path;
        for (const fs::path& candidate : candidates) {
            path = candidate;
            if ((handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL))) break;
            const char* why = dlerror();
            error += (error.empty() ? "" : "; ") + std::string(why ? why : path.c_str());
        }
        if (!handle) return;
        error.clear();
        auto entry = reinterpret_cast<OiioModuleEntry>(dlsym(handle, FEMTO_OIIO_ENTRY));
        const OiioModule* found = entry ? entry() : nullptr;
        if (!found || found->version != kOiioModuleVersion) {
            error = fmt::format("{} is not this build's module", path.string());
            return;
        }
        module = found;
    });
    if (!module)  // an incomplete installation: the message names the files tried
        throw SceneError(fmt::format("cannot load femto's OpenImageIO module: {}", error));
    return *module;
}

}  // namespace detail

using detail::temp_path_for;

namespace {

void commit(const std::string& tmp, const std::string& path) { detail::commit_file(tmp, path); }

// Writes 8-bit sRGB pixels (rows top first, 3 bytes a pixel) as a PNG file through libpng;
// returns "" or what went wrong.
std::string write_png_rgb8(const std::string& path, int width, int height,
                           const unsigned char* rgb) {
    png_image image{};
    image.version = PNG_IMAGE_VERSION;
    image.width = png_uint_32(width);
    image.height = png_uint_32(height);
    image.format = PNG_FORMAT_RGB;  // 8-bit sRGB: libpng marks the file so (an sRGB chunk)
    if (png_image_write_to_file(&image, path.c_str(), 0, rgb, 0, nullptr)) return {};
    const std::string error = image.message[0] ? image.message : "unknown error";
    png_image_free(&image);
    return error;
}

std::string exe_relative_config() {
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&ocio_config_path), &info) && info.dli_fname) {
        std::error_code ec;
        const fs::path lib = fs::canonical(info.dli_fname, ec);
        if (!ec) {
            const fs::path installed =
                lib.parent_path().parent_path() / "share" / FEMTO_OCIO_INSTALL_SUBDIR;
            if (fs::exists(installed, ec)) return installed.string();
        }
    }
    return {};
}

}  // namespace

namespace detail {

void insert_attribute(Imf::Header& header, const std::string& key, const std::string& value) {
    // A later value of a key replaces an earlier one (a viz option overriding the cube's), even
    // when its text reads as another type ("6" after "6.5"), which OpenEXR refuses to insert.
    if (header.find(key) != header.end()) header.erase(key);
    const char* first = value.data();
    const char* last = first + value.size();
    int i = 0;
    if (auto [p, ec] = std::from_chars(first, last, i); ec == std::errc() && p == last) {
        header.insert(key, Imf::IntAttribute(i));
        return;
    }
    const bool integer_text =
        !value.empty() && value.find_first_not_of("+-0123456789") == std::string::npos;
    double d = 0;
    if (auto [p, ec] = std::from_chars(first, last, d);
        !integer_text && ec == std::errc() && p == last && std::isfinite(d)) {
        header.insert(key, Imf::DoubleAttribute(d));
        return;
    }
    header.insert(key, Imf::StringAttribute(value));
}

}  // namespace detail

std::string ocio_config_path() {
    if (const char* env = std::getenv("FEMTO_OCIO_CONFIG"); env && *env) return env;
    std::string installed = exe_relative_config();
    if (!installed.empty()) return installed;
    return FEMTO_SOURCE_OCIO_CONFIG;
}

void write_exr_rgb(const std::string& path, int width, int height, const float* rgb,
                   const Attributes& attributes, const float* depth, const ExtraChannels& extra) {
    for (size_t k = 0; k < extra.names.size(); ++k) {
        const std::string& n = extra.names[k];
        const bool taken = n == "R" || n == "G" || n == "B" || (depth && n == "Z") ||
                           std::find(extra.names.begin(), extra.names.begin() + long(k), n) !=
                               extra.names.begin() + long(k);
        if (n.empty() || taken)
            throw SceneError(
                fmt::format("cannot write \"{}\": EXR channel name \"{}\" is empty "
                            "or used twice",
                            path, n));
    }
    std::vector<detail::ExrChannel> channels;
    for (size_t c = 0; c < 3; ++c) channels.push_back({std::string(1, "RGB"[c]), rgb + c, 3});
    if (depth) channels.push_back({"Z", depth, 1});
    for (size_t k = 0; k < extra.names.size(); ++k)
        channels.push_back({extra.names[k], extra.data + k, extra.names.size()});
    detail::write_exr_channels(path, width, height, channels, attributes);
}

namespace detail {

void write_exr_channels(const std::string& path, int width, int height,
                        const std::vector<ExrChannel>& channels, const Attributes& attributes) {
    const std::string tmp = temp_path_for(path);
    try {
        Imf::Header header(width, height);
        header.compression() = Imf::ZIP_COMPRESSION;
        for (const ExrChannel& c : channels)
            header.channels().insert(c.name, Imf::Channel(Imf::FLOAT));
        for (const auto& [k, v] : attributes) insert_attribute(header, k, v);
        Imf::FrameBuffer fb;
        for (const ExrChannel& c : channels)
            fb.insert(
                c.name,
                Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(c.first)),
                           c.stride * sizeof(float), c.stride * sizeof(float) * size_t(width)));
        Imf::OutputFile file(tmp.c_str(), header);
        file.setFrameBuffer(fb);
        file.writePixels(height);
    } catch (const std::exception& e) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw SceneError(fmt::format("cannot write \"{}\": {}", path, e.what()));
    }
    commit(tmp, path);
}

std::vector<unsigned char> display_bytes(const std::vector<float>& display) {
    std::vector<unsigned char> bytes(display.size());
    for (size_t i = 0; i < bytes.size(); ++i)
        bytes[i] = static_cast<unsigned char>(std::lround(
            std::clamp(std::isfinite(display[i]) ? display[i] : 0.f, 0.f, 1.f) * 255.f));
    return bytes;
}

void write_png_display(const std::string& path, int width, int height,
                       const std::vector<float>& display) {
    const std::vector<unsigned char> bytes = display_bytes(display);
    const std::string tmp = temp_path_for(path);
    if (const std::string err = write_png_rgb8(tmp, width, height, bytes.data()); !err.empty()) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw SceneError(fmt::format("cannot write \"{}\": {}", path, err));
    }
    commit(tmp, path);
}

}  // namespace detail

void write_png_preview(const std::string& path, int width, int height, const float* rgb,
                       float exposure) {
    const size_t n = size_t(width) * size_t(height);
    std::vector<float> buf(rgb, rgb + 3 * n);
    const float scale = std::exp2(exposure);
    for (float& v : buf) v = std::isfinite(v) ? std::max(0.f, v * scale) : 0.f;
    OCIO::PackedImageDesc desc(buf.data(), width, height, 3);
    detail::display_processor()->apply(desc);
    detail::write_png_display(path, width, height, buf);
}

namespace {

constexpr int kMaxImageSide = 1 << 16;
constexpr int64_t kMaxImagePixels = int64_t(1) << 28;

// OpenEXR allocates scanline buffers for the width a header claims while opening the file,
// before OpenImageIO hands femto the spec: a corrupt header could ask for gigabytes. Its own
// limit makes such files fail at the header instead. The limit is process-wide and OpenEXR
// checks it on writing too, so it bounds widths only (0: no limit on heights): femto's cubes
// stack their frames as rows, height x bins of them, far beyond any image's height.
void limit_openexr_sizes() {
    static std::once_flag once;
    std::call_once(once, [] {
        Imf::Header::setMaxImageSize(kMaxImageSide, 0);
        Imf::Header::setMaxTileSize(kMaxImageSide, 0);
    });
}

// libpng, inside OpenImageIO, prints "libpng error: ..." straight to stderr before OpenImageIO
// turns the failure into the error message that femto reports itself, with the scene location.
// While an image is decoded, stderr goes to a temporary file; what was printed is passed on
// only when the image was read (libpng's warnings), and dropped when femto reports an error.
class HeldStderr {
public:
    HeldStderr() {
        std::fflush(stderr);
        held_ = std::tmpfile();
        saved_ = held_ ? ::dup(STDERR_FILENO) : -1;
        if (saved_ >= 0 && ::dup2(::fileno(held_), STDERR_FILENO) < 0) {
            ::close(saved_);
            saved_ = -1;
        }
    }
    ~HeldStderr() {
        release(true);
        if (held_) std::fclose(held_);
    }
    HeldStderr(const HeldStderr&) = delete;
    HeldStderr& operator=(const HeldStderr&) = delete;

    /// Gives stderr back; with `pass_on`, writes to it what was printed meanwhile.
    void release(bool pass_on) {
        if (saved_ < 0) return;
        std::fflush(stderr);
        ::dup2(saved_, STDERR_FILENO);
        ::close(saved_);
        saved_ = -1;
        if (!pass_on) return;
        std::rewind(held_);
        char buffer[4096];
        for (size_t n; (n = std::fread(buffer, 1, sizeof buffer, held_)) > 0;)
            std::fwrite(buffer, 1, n, stderr);
    }

private:
    std::FILE* held_ = nullptr;
    int saved_ = -1;
};

}  // namespace

namespace detail {

namespace {

// The sizes OpenEXR 3.1 reads attributes of fixed-size types by, whatever size is declared.
int64_t fixed_attribute_size(const std::string& type) {
    static const std::map<std::string, int64_t> sizes = {{"box2i", 16},
                                                         {"box2f", 16},
                                                         {"chromaticities", 32},
                                                         {"compression", 1},
                                                         {"deepImageState", 1},
                                                         {"double", 8},
                                                         {"envmap", 1},
                                                         {"float", 4},
                                                         {"int", 4},
                                                         {"keycode", 28},
                                                         {"lineOrder", 1},
                                                         {"m33f", 36},
                                                         {"m33d", 72},
                                                         {"m44f", 64},
                                                         {"m44d", 128},
                                                         {"rational", 8},
                                                         {"tiledesc", 9},
                                                         {"timecode", 8},
                                                         {"v2i", 8},
                                                         {"v2f", 8},
                                                         {"v2d", 16},
                                                         {"v3i", 12},
                                                         {"v3f", 12},
                                                         {"v3d", 24}};
    const auto it = sizes.find(type);
    return it == sizes.end() ? -1 : it->second;
}

// Reads a null-terminated name of at most 255 characters.
bool read_exr_name(std::istream& in, std::string& s) {
    s.clear();
    for (char c; in.get(c);) {
        if (c == '\0') return true;
        if (s.size() == 255) return false;
        s.push_back(c);
    }
    return false;
}

int32_t read_le32(const unsigned char* b) {
    return int32_t(uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 |
                   uint32_t(b[3]) << 24);
}

// What one header says of the size of its pixel blocks (chunks).
struct ChunkLayout {
    int64_t channel_bytes = 0;       // a pixel's bytes over all channels
    int64_t width = 0;               // the data window's (0: not known)
    int64_t tile_w = 0, tile_h = 0;  // 0 without a tile description
    int compression = 0;
    // The MiB OpenEXR decodes one chunk into, and allocates such a buffer per thread on
    // opening the file: a tile, or a block of scanlines (as many as the compression groups).
    // In double: a header's sizes can make any integer product overflow.
    double tile_mebibytes() const {
        return double(tile_w) * double(tile_h) * double(channel_bytes) / double(1 << 20);
    }
    double scanline_mebibytes() const {
        static constexpr int kLinesPerBlock[] = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};
        const int lines = compression >= 0 && compression < 10 ? kLinesPerBlock[compression] : 1;
        return double(width) * lines * double(channel_bytes) / double(1 << 20);
    }
};

// Notes attribute `name` of type `type`, whose value starts at the stream's position, in
// `layout` when it tells a chunk's size; leaves the position where it was.
void note_chunk_attribute(std::istream& in, const std::string& name, const std::string& type,
                          ChunkLayout& layout) {
    char v[16] = {};
    const auto* b = reinterpret_cast<const unsigned char*>(v);
    const std::streampos at = in.tellg();
    if (name == "dataWindow" && type == "box2i" && in.read(v, 16))
        layout.width = std::max<int64_t>(0, int64_t(read_le32(b + 8)) - read_le32(b) + 1);
    else if (name == "tiles" && type == "tiledesc" && in.read(v, 9))
        layout.tile_w = uint32_t(read_le32(b)), layout.tile_h = uint32_t(read_le32(b + 4));
    else if (name == "compression" && type == "compression" && in.read(v, 1))
        layout.compression = b[0];
    in.clear();
    in.seekg(at);
}

// The most a pixel block may take decoded. femto's cubes use tiles of at most 256 kB; a tile
// of 2048 x 2048 float RGBA pixels is 64 MiB, and a 32768-pixel-wide scanline block of 256
// lines (DWAB) of half RGBA 64 MiB. A 538-byte file declaring tiles of 16388 x 4096 made
// OpenEXR allocate 805 MB per buffer (the cube fuzzer: 10 s an input under ASan).
constexpr double kMaxChunkMebibytes = 256;

}  // namespace

std::string exr_header_problem(const std::string& path) {
    // Every reader asks here before it opens a file with OpenEXR: its limits then hold too.
    limit_openexr_sizes();
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    const std::streamoff file_size = in.tellg();
    unsigned char version[8] = {};
    if (!in || !in.seekg(0).read(reinterpret_cast<char*>(version), 8)) return {};
    const bool multipart = (version[5] & 0x10) != 0;  // bit 12 of the version field
    for (;;) {  // headers: one, or (multi-part) several and then an empty one
        bool empty = true;
        ChunkLayout chunk;
        for (std::string name, type;;) {
            if (!read_exr_name(in, name)) return {};
            if (name.empty()) break;
            empty = false;
            unsigned char b[4];
            if (!read_exr_name(in, type) || !in.read(reinterpret_cast<char*>(b), 4)) return {};
            const int64_t size = read_le32(b);
            if (type == "chlist") {  // channels (a name and 16 bytes) up to an empty name
                for (std::string channel; read_exr_name(in, channel) && !channel.empty();) {
                    unsigned char c[16];
                    if (!in.read(reinterpret_cast<char*>(c), 16)) return {};
                    chunk.channel_bytes += read_le32(c) == 1 ? 2 : 4;  // HALF, else UINT / FLOAT
                }
                if (!in) return {};
                continue;
            }
            note_chunk_attribute(in, name, type, chunk);
            const int64_t fixed = fixed_attribute_size(type);
            const std::streamoff left = file_size - in.tellg();
            if (fixed < 0 && (size < 0 || size > left))
                return fmt::format(
                    "its header attribute \"{}\" declares {} bytes, and the file "
                    "holds {} more",
                    name, size, left);
            in.seekg(fixed < 0 ? size : fixed, std::ios::cur);
        }
        // Whether the part is tiled is left open (a single part's version flag, a part's type
        // attribute, either of which a corrupt file may contradict): both block sizes must
        // fit. Blocks wider than OpenEXR's limit it refuses itself (limit_openexr_sizes()).
        if (!empty && chunk.tile_w <= kMaxImageSide && chunk.tile_mebibytes() > kMaxChunkMebibytes)
            return fmt::format(
                "its tiles of {} x {} pixels would take {:.0f} MiB each to decode "
                "(at most {:.0f} MiB)",
                chunk.tile_w, chunk.tile_h, chunk.tile_mebibytes(), kMaxChunkMebibytes);
        if (!empty && chunk.width <= kMaxImageSide &&
            chunk.scanline_mebibytes() > kMaxChunkMebibytes)
            return fmt::format(
                "its blocks of scanlines, {} pixels wide, would take {:.0f} MiB "
                "each to decode (at most {:.0f} MiB)",
                chunk.width, chunk.scanline_mebibytes(), kMaxChunkMebibytes);
        if (!multipart || empty) return {};
    }
}

}  // namespace detail

namespace {

// An EXR file with R, G and B channels of half or float values, read through OpenEXR as
// OpenImageIO would read it (its data window, channels by name), so that an EXR texture or
// environment map does not load OpenImageIO (~0.4 s). nullopt for any other file (not an EXR,
// or other channels), which OpenImageIO reads. An EXR whose header OpenEXR refuses is an
// error here: OpenImageIO reads EXRs through the same library, and would only add its load
// time (under the fuzzers' sanitizers, seconds per input) and its prefix to OpenEXR's message.
std::optional<std::vector<float>> read_rgb_exr(const std::string& path, int& width, int& height) {
    char magic[4] = {};
    if (!std::ifstream(path, std::ios::binary).read(magic, 4) ||
        std::string(magic, 4) != "\x76\x2f\x31\x01")
        return std::nullopt;
    if (const std::string problem = detail::exr_header_problem(path); !problem.empty())
        throw SceneError(fmt::format("cannot read image \"{}\": {}", path, problem));
    std::unique_ptr<Imf::InputFile> file;
    try {
        file = std::make_unique<Imf::InputFile>(path.c_str());
    } catch (const std::exception& e) {
        throw SceneError(fmt::format("cannot read image \"{}\": {}", path, e.what()));
    }
    const Imf::Header& header = file->header();
    const char* names[3] = {"R", "G", "B"};
    for (const char* name : names) {
        const Imf::Channel* c = header.channels().findChannel(name);
        if (!c || !(c->type == Imf::HALF || c->type == Imf::FLOAT) || c->xSampling != 1 ||
            c->ySampling != 1)
            return std::nullopt;
    }
    const Imath::Box2i dw = header.dataWindow();
    const int64_t w = int64_t(dw.max.x) - dw.min.x + 1, h = int64_t(dw.max.y) - dw.min.y + 1;
    if (w <= 0 || h <= 0 || w * h > kMaxImagePixels)
        throw SceneError(
            fmt::format("cannot read image \"{}\": unsupported size {}x{}x3 (at most "
                        "{} pixels)",
                        path, w, h, kMaxImagePixels));
    try {
        detail::require_whole_exr(*file, dw, {"R", "G", "B"});
    } catch (const std::exception& e) {
        throw SceneError(fmt::format("cannot read image \"{}\": {}", path, e.what()));
    }
    std::vector<float> rgb(size_t(w) * size_t(h) * 3);
    Imf::FrameBuffer fb;
    for (size_t c = 0; c < 3; ++c)
        fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, rgb.data() + c, dw.min, w, h,
                                             3 * sizeof(float), 3 * sizeof(float) * size_t(w)));
    try {
        file->setFrameBuffer(fb);
        file->readPixels(dw.min.y, dw.max.y);
    } catch (const std::exception& e) {
        throw SceneError(fmt::format("cannot read image \"{}\": {}", path, e.what()));
    }
    width = int(w);
    height = int(h);
    return rgb;
}

}  // namespace

std::vector<float> read_image_rgb(const std::string& path, int& width, int& height,
                                  bool srgb_8bit) {
    if (const std::string problem = input_file_problem(path); !problem.empty())
        throw SceneError(fmt::format("cannot read image \"{}\": {}", path, problem));
    limit_openexr_sizes();
    if (std::optional<std::vector<float>> rgb = read_rgb_exr(path, width, height))
        return std::move(*rgb);
    const detail::OiioModule& oiio = detail::oiio_module();  // before stderr is held
    detail::DecodedImage image;
    HeldStderr held;
    const std::string error = oiio.decode(path, kMaxImagePixels, image);
    held.release(error.empty());
    if (!error.empty()) throw SceneError(fmt::format("cannot read image \"{}\": {}", path, error));
    width = image.width;
    height = image.height;
    const int nc = image.channels;
    const float* pixels = image.pixels.get();
    const bool decode = srgb_8bit && image.integer_8_or_16;
    std::vector<float> rgb(size_t(width) * height * 3);
    for (size_t i = 0; i < size_t(width) * height; ++i)
        for (int c = 0; c < 3; ++c) {
            float v = pixels[i * nc + (nc >= 3 ? c : 0)];
            rgb[3 * i + c] = decode ? srgb_to_linear(v) : v;
        }
    return rgb;
}

}  // namespace femto::io

// ---- time-resolved images ---------------------------------------------------------------

#include <OpenEXR/ImfFloatAttribute.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfThreading.h>
#include <OpenEXR/ImfTileDescriptionAttribute.h>
#include <OpenEXR/ImfTiledInputPart.h>
#include <OpenEXR/ImfTiledOutputPart.h>

#include <cstring>
#include <fstream>
#include <limits>
#include <thread>

namespace femto::io {

const std::string* Cube::attribute(const std::string& name) const {
    for (const auto& [k, v] : attributes)
        if (k == name) return &v;
    return nullptr;
}

namespace detail {

Attributes read_attributes(const Imf::Header& header) {
    Attributes out;
    for (auto it = header.begin(); it != header.end(); ++it) {
        const Imf::Attribute& a = it.attribute();
        const std::string name = it.name();
        if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&a)) {
            if (name != "name" && name != "type") out.emplace_back(name, s->value());
        } else if (name.rfind("femto:", 0) != 0) {
            continue;
        } else if (const auto* i = dynamic_cast<const Imf::IntAttribute*>(&a))
            out.emplace_back(it.name(), std::to_string(i->value()));
        else if (const auto* d = dynamic_cast<const Imf::DoubleAttribute*>(&a))
            out.emplace_back(it.name(), fmt::format("{}", d->value()));
        else if (const auto* f = dynamic_cast<const Imf::FloatAttribute*>(&a))
            out.emplace_back(it.name(), fmt::format("{}", f->value()));
    }
    return out;
}

}  // namespace detail

namespace {

Imf::Compression exr_compression(ExrCubeOptions::Compression c) {
    using C = ExrCubeOptions::Compression;
    switch (c) {
        case C::none:
            return Imf::NO_COMPRESSION;
        case C::rle:
            return Imf::RLE_COMPRESSION;
        case C::zips:
            return Imf::ZIPS_COMPRESSION;
        case C::zip:
            return Imf::ZIP_COMPRESSION;
        case C::piz:
            return Imf::PIZ_COMPRESSION;
    }
    return Imf::RLE_COMPRESSION;
}

// OpenEXR compresses a file's chunks (tiles of the frames part) as tasks of its global thread
// pool; chunks under 64 kB cost more as tasks than they save, so they stay on this thread.
void set_exr_threads(const ExrCubeOptions& options, size_t chunk_bytes) {
    int n = options.threads > 0 ? options.threads
                                : int(std::max(1u, std::thread::hardware_concurrency()));
    if (chunk_bytes < (size_t(64) << 10)) n = 1;
    if (Imf::globalThreadCount() != (n > 1 ? n : 0)) Imf::setGlobalThreadCount(n > 1 ? n : 0);
}

void insert_rgb(Imf::FrameBuffer& fb, const float* first, Imath::V2i origin, int w, int h,
                size_t xs, size_t ys) {
    const char* base = reinterpret_cast<const char*>(first);
    const char* names[] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c)
        fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, base + size_t(c) * sizeof(float), origin,
                                             w, h, xs, ys));
}

struct CubeView {
    int width, height, bins;
    size_t pixels() const { return size_t(width) * size_t(height); }
    // Element (pixel, bin, 0) of a [pixel][bin][3] cube.
    size_t at(size_t pixel, int bin) const { return (pixel * size_t(bins) + size_t(bin)) * 3; }
};

int64_t floor_div(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Rows [r0, r1) of the strip (row t * height + y is row y of bin t's frame), each value times
// its pixel's scale, into out ([row][x][3]). The cube is pixel-major, so the loop runs over
// pixels and, for each, over its consecutive bins in the batch: one pass over the cube in runs
// of several bins, not a cache line per value.
void gather_strip_rows(const CubeView& v, const float* data, const float* pixel_scale, int64_t r0,
                       int64_t r1, float* out) {
    const int64_t H = v.height;
    for (int y = 0; y < v.height; ++y) {
        // The bins t whose row t * H + y lies in [r0, r1).
        const int64_t t_lo = std::max<int64_t>(0, -floor_div(y - r0, H));
        const int64_t t_hi = floor_div(r1 - 1 - y, H);
        if (t_lo > t_hi) continue;
        for (int x = 0; x < v.width; ++x) {
            const size_t pixel = size_t(y) * size_t(v.width) + size_t(x);
            const float* src = data + v.at(pixel, int(t_lo));
            // Each pixel's run starts a whole pixel's bins (kilobytes) past the last, a cache
            // miss the loop waits on. With the cube in huge pages it waited longer
            // (femto_bench_write's uncompressed cube: 0.19 s in 4 KiB pages, 0.27-0.32 s in
            // huge pages); asking 8 pixels ahead gives 0.18-0.21 s.
            if (x + 8 < v.width) {
                const float* ahead = data + v.at(pixel + 8, int(t_lo));
                __builtin_prefetch(ahead);
                __builtin_prefetch(ahead + 3 * (t_hi - t_lo));
            }
            const float s = pixel_scale ? pixel_scale[pixel] : 1.f;
            for (int64_t t = t_lo; t <= t_hi; ++t) {
                float* dst = out + (size_t(t * H + y - r0) * size_t(v.width) + size_t(x)) * 3;
                for (int c = 0; c < 3; ++c) dst[c] = src[(t - t_lo) * 3 + c] * s;
            }
        }
    }
}

// Reading: frames [t0, t0 + n), whole frames ([t][y][x][3]), into the cube.
void scatter_frames(const CubeView& v, const float* in, int t0, int n, float* data) {
    const size_t pixels = v.pixels();
    for (size_t pixel = 0; pixel < pixels; ++pixel) {
        float* dst = data + v.at(pixel, t0);
        if (pixel + 8 < pixels) {  // as in gather_strip_rows()
            float* ahead = data + v.at(pixel + 8, t0);
            __builtin_prefetch(ahead, 1);
            __builtin_prefetch(ahead + 3 * (n - 1), 1);
        }
        for (int k = 0; k < n; ++k)
            for (int c = 0; c < 3; ++c) dst[k * 3 + c] = in[(size_t(k) * pixels + pixel) * 3 + c];
    }
}

// The strip is tiled: OpenEXR keeps two tables with an entry per scanline while writing a
// scanline image (24 bytes a row: an eighth of a 16-pixel-wide film's data), but only an offset
// per tile for a tiled one. Tiles of 64-256 kB also make worthwhile tasks for OpenEXR's pool.
struct StripTiling {
    int tile_w, tile_h;
    explicit StripTiling(int width) : tile_w(std::min(width, 256)), tile_h(16) {
        while (tile_h < 4096 &&
               size_t(tile_w) * size_t(tile_h) * 2 * 3 * sizeof(float) <= (size_t(256) << 10))
            tile_h *= 2;
    }
    size_t tile_bytes() const { return size_t(tile_w) * size_t(tile_h) * 3 * sizeof(float); }
};

// Strip rows per batch: whole tile rows, ~8 MB (several bins of every pixel per pass over the
// cube), at most 1/16 of the cube when that is larger than one tile row.
int64_t strip_batch_rows(const CubeView& v, const StripTiling& tiling) {
    const size_t row_bytes = size_t(v.width) * 3 * sizeof(float);
    const size_t cube_bytes = v.pixels() * size_t(v.bins) * 3 * sizeof(float);
    const size_t target = std::min(size_t(8) << 20, cube_bytes / 16);
    const int64_t tile_rows = std::max<int64_t>(1, int64_t(target / row_bytes) / tiling.tile_h);
    return std::min(tile_rows * tiling.tile_h, int64_t(v.height) * v.bins);
}

// Parts of one file must share a display window: both parts use the frames' (the whole
// strip), the depth part's data window being its first frame's place.
// With `tiling` the part is tiled (the frames), else scanline (the depth).
Imf::Header cube_part_header(const std::string& name, int width, int rows, int strip_rows,
                             const ExrCubeOptions& options, const StripTiling* tiling = nullptr) {
    Imf::Header h(Imath::Box2i({0, 0}, {width - 1, strip_rows - 1}),
                  Imath::Box2i({0, 0}, {width - 1, rows - 1}));
    h.setName(name);
    h.setType(tiling ? Imf::TILEDIMAGE : Imf::SCANLINEIMAGE);
    if (tiling)
        h.setTileDescription(Imf::TileDescription(unsigned(tiling->tile_w),
                                                  unsigned(tiling->tile_h), Imf::ONE_LEVEL));
    h.compression() = exr_compression(options.compression);
    h.zipCompressionLevel() = std::clamp(options.zip_level, 1, 9);
    return h;
}

void write_frames_part(Imf::MultiPartOutputFile& file, const CubeView& v, const float* data,
                       const float* pixel_scale, const StripTiling& tiling) {
    Imf::TiledOutputPart part(file, 0);
    const int64_t rows = int64_t(v.height) * v.bins, batch = strip_batch_rows(v, tiling);
    const size_t xs = 3 * sizeof(float), ys = xs * size_t(v.width);
    std::vector<float> buffer(size_t(batch) * size_t(v.width) * 3);
    for (int64_t r0 = 0; r0 < rows; r0 += batch) {
        const int64_t r1 = std::min(rows, r0 + batch);
        gather_strip_rows(v, data, pixel_scale, r0, r1, buffer.data());
        Imf::FrameBuffer fb;
        insert_rgb(fb, buffer.data(), Imath::V2i(0, int(r0)), v.width, int(r1 - r0), xs, ys);
        part.setFrameBuffer(fb);
        part.writeTiles(0, part.numXTiles() - 1, int(r0 / tiling.tile_h),
                        int((r1 - 1) / tiling.tile_h));
    }
}

}  // namespace

bool parse_exr_compression(const std::string& name, ExrCubeOptions::Compression& out) {
    using C = ExrCubeOptions::Compression;
    static const std::pair<const char*, C> names[] = {
        {"none", C::none}, {"rle", C::rle}, {"zips", C::zips}, {"zip", C::zip}, {"piz", C::piz}};
    for (const auto& [n, c] : names)
        if (name == n) {
            out = c;
            return true;
        }
    return false;
}

void write_exr_cube(const std::string& path, int width, int height, int bins, const float* data,
                    const float* depth, const Attributes& attributes, const float* pixel_scale,
                    const ExrCubeOptions& options) {
    if (int64_t(height) * bins > std::numeric_limits<int>::max())
        throw SceneError(
            fmt::format("cannot write \"{}\": {} rows x {} bins exceed an EXR image's {} rows",
                        path, height, bins, std::numeric_limits<int>::max()));
    const std::string tmp = temp_path_for(path);
    try {
        const StripTiling tiling(width);
        set_exr_threads(options, tiling.tile_bytes());
        std::vector<Imf::Header> headers;
        headers.push_back(
            cube_part_header("frames", width, height * bins, height * bins, options, &tiling));
        for (const char* c : {"R", "G", "B"})
            headers[0].channels().insert(c, Imf::Channel(Imf::FLOAT));
        for (const auto& [k, v] : attributes) detail::insert_attribute(headers[0], k, v);
        detail::insert_attribute(headers[0], "femto:frame_height", std::to_string(height));
        headers[0].insert("femto:layout",
                          Imf::StringAttribute("frames stacked top to bottom: bin t is rows "
                                               "[t * femto:frame_height, (t + 1) * "
                                               "femto:frame_height)"));
        if (depth) {
            headers.push_back(cube_part_header("depth", width, height, height * bins, options));
            headers[1].channels().insert("Z", Imf::Channel(Imf::FLOAT));
        }
        Imf::MultiPartOutputFile file(tmp.c_str(), headers.data(), int(headers.size()));
        write_frames_part(file, CubeView{width, height, bins}, data, pixel_scale, tiling);
        if (depth) {
            Imf::OutputPart part(file, 1);
            Imf::FrameBuffer fb;
            fb.insert("Z", Imf::Slice::Make(Imf::FLOAT, depth, Imath::V2i(0, 0), width, height,
                                            sizeof(float), sizeof(float) * size_t(width)));
            part.setFrameBuffer(fb);
            part.writePixels(height);
        }
    } catch (const std::exception& e) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw SceneError(fmt::format("cannot write \"{}\": {}", path, e.what()));
    }
    commit(tmp, path);
}

namespace {

Imath::Box2i checked_window(const Imf::Header& h, int64_t width, int64_t height) {
    const Imath::Box2i w = h.dataWindow();
    if (int64_t(w.max.x) - w.min.x + 1 != width || int64_t(w.max.y) - w.min.y + 1 != height)
        throw std::runtime_error(fmt::format("part \"{}\" is not {}x{} pixels",
                                             h.hasName() ? h.name() : "", width, height));
    return w;
}

// (read_exr_cube() checked the part's window before allocating the cube.)
void read_depth_part(Imf::MultiPartInputFile& file, int p, Cube& cube) {
    const Imath::Box2i w = file.header(p).dataWindow();
    cube.depth.assign(size_t(cube.width) * size_t(cube.height), -1.f);
    Imf::InputPart part(file, p);
    Imf::FrameBuffer fb;
    fb.insert("Z", Imf::Slice::Make(Imf::FLOAT, cube.depth.data(), w.min, cube.width, cube.height,
                                    sizeof(float), sizeof(float) * size_t(cube.width)));
    part.setFrameBuffer(fb);
    part.readPixels(w.min.y, w.max.y);
}

// Rows per tile of a frames part that read_frames_part() reads by whole tile rows: 0 for a
// scanline part, or for tiles too tall to buffer (a file from elsewhere: beyond 16 MiB a tile
// row), which go through the scanline interface. OpenEXR keeps the interface a part was first
// opened with (a TiledInputPart of a part first opened as an InputPart crashed), so the
// whole-file check and the read both ask this.
int frames_tile_rows(const Imf::Header& h, int width) {
    if (!h.hasTileDescription()) return 0;
    const size_t rows = h.tileDescription().ySize;
    return rows * size_t(width) * 3 * sizeof(float) <= (size_t(16) << 20) ? int(rows) : 0;
}

// require_whole_exr() for a part read by tiles: its offset table whole, and its first and last
// tile rows decoded into scratch (a cut file lacks the last).
void require_whole_tiles(Imf::TiledInputPart& part, const Imath::Box2i& dw, int tile_h) {
    detail::require_complete(part);
    const int width = dw.max.x - dw.min.x + 1;
    std::vector<float> rows(size_t(width) * size_t(tile_h) * 3);
    const size_t xs = 3 * sizeof(float), ys = xs * size_t(width);
    for (const int ty : {0, part.numYTiles() - 1}) {
        Imf::FrameBuffer fb;
        insert_rgb(fb, rows.data(), Imath::V2i(dw.min.x, dw.min.y + ty * tile_h), width, tile_h, xs,
                   ys);
        part.setFrameBuffer(fb);
        part.readTiles(0, part.numXTiles() - 1, ty, ty);
    }
}

// The stacked-frames layout (part "frames"), read back a batch of whole frames at a time. A
// tiled strip (what write_exr_cube() writes) is read by whole tile rows: through the scanline
// interface OpenEXR copies each tile into a line buffer first (about a quarter of `femto viz
// peak-time`'s time on a 805 MB cube). A tile row on a batch's edge is read by both batches.
// (read_exr_cube() checked the part's window before allocating the cube.)
void read_frames_part(Imf::MultiPartInputFile& file, int p, Cube& cube) {
    const CubeView v{cube.width, cube.height, cube.bins};
    const Imath::Box2i w = file.header(p).dataWindow();
    const size_t frame_bytes = v.pixels() * 3 * sizeof(float);
    const int frames =
        int(std::clamp<size_t>((size_t(8) << 20) / frame_bytes, 1, size_t(cube.bins)));
    const int tile_h = frames_tile_rows(file.header(p), cube.width);
    std::vector<float> buffer((size_t(frames) * size_t(cube.height) + 2 * size_t(tile_h)) *
                              size_t(cube.width) * 3);
    const size_t xs = 3 * sizeof(float), ys = xs * size_t(cube.width);
    std::optional<Imf::TiledInputPart> tiles;
    std::optional<Imf::InputPart> lines;
    if (tile_h > 0)
        tiles.emplace(file, p);
    else
        lines.emplace(file, p);
    for (int t0 = 0; t0 < cube.bins; t0 += frames) {
        const int n = std::min(frames, cube.bins - t0);
        const int first = w.min.y + t0 * cube.height, last = first + n * cube.height - 1;
        Imf::FrameBuffer fb;
        size_t skip = 0;  // buffer rows before the batch's first
        if (tiles) {
            const int ty0 = (first - w.min.y) / tile_h, ty1 = (last - w.min.y) / tile_h;
            const int row0 = w.min.y + ty0 * tile_h;
            insert_rgb(fb, buffer.data(), Imath::V2i(w.min.x, row0), cube.width,
                       (ty1 - ty0 + 1) * tile_h, xs, ys);
            tiles->setFrameBuffer(fb);
            tiles->readTiles(0, tiles->numXTiles() - 1, ty0, ty1);
            skip = size_t(first - row0);
        } else {
            insert_rgb(fb, buffer.data(), Imath::V2i(w.min.x, first), cube.width, n * cube.height,
                       xs, ys);
            lines->setFrameBuffer(fb);
            lines->readPixels(first, last);
        }
        scatter_frames(v, buffer.data() + skip * size_t(cube.width) * 3, t0, n, cube.data.data());
    }
}

// The layout of femto before the stacked frames: one RGB part per bin, named t00000, ...
void read_legacy_bin_part(Imf::MultiPartInputFile& file, int p, Cube& cube) {
    const std::string name = file.header(p).name();
    const int bin = std::stoi(name.substr(1));
    if (bin < 0 || bin >= cube.bins)
        throw std::runtime_error("a part name is out of range: " + name);
    const Imath::Box2i w = checked_window(file.header(p), cube.width, cube.height);
    const size_t xs = size_t(cube.bins) * 3 * sizeof(float), ys = xs * size_t(cube.width);
    Imf::InputPart part(file, p);
    Imf::FrameBuffer fb;
    insert_rgb(fb, cube.data.data() + size_t(bin) * 3, w.min, cube.width, cube.height, xs, ys);
    part.setFrameBuffer(fb);
    part.readPixels(w.min.y, w.max.y);
}

bool is_legacy_bin_part(const Imf::Header& h) {
    return h.hasName() && h.name().size() == 6 && h.name()[0] == 't' &&
           h.name().find_first_not_of("0123456789", 1) == std::string::npos;
}

int int_attribute(const Attributes& attributes, const std::string& name) {
    for (const auto& [k, v] : attributes)
        if (k == name) {
            int value = 0;
            auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), value);
            if (ec == std::errc() && p == v.data() + v.size() && value > 0) return value;
            throw std::runtime_error(fmt::format("attribute {} is \"{}\"", name, v));
        }
    throw std::runtime_error(fmt::format("attribute {} is missing", name));
}

}  // namespace

Cube read_exr_cube(const std::string& path) {
    // OpenEXR opens the file itself: refuse first what would block it (a FIFO) or never end.
    if (const std::string problem = input_file_problem(path); !problem.empty())
        throw SceneError(fmt::format("cannot read transient EXR \"{}\": {}", path, problem));
    Cube cube;
    try {
        if (const std::string problem = detail::exr_header_problem(path); !problem.empty())
            throw std::runtime_error(problem);
        // Decoding a cube's tiles is most of reading it: on OpenEXR's pool, one thread a core.
        set_exr_threads(ExrCubeOptions{}, size_t(64) << 10);
        Imf::MultiPartInputFile file(path.c_str(), Imf::globalThreadCount());
        const int parts = file.parts();
        int frames_part = -1, depth_part = -1, legacy_bins = 0;
        for (int p = 0; p < parts; ++p) {
            const Imf::Header& h = file.header(p);
            if ((h.hasName() && h.name() == "frames") ||
                h.findTypedAttribute<Imf::IntAttribute>("femto:frame_height"))
                frames_part = p;
            if (h.hasName() && h.name() == "depth") depth_part = p;
            if (is_legacy_bin_part(h)) ++legacy_bins;
        }
        if (frames_part < 0 && legacy_bins == 0)
            throw std::runtime_error("it is not a femto transient cube (no part named \"frames\")");
        const Imf::Header& first = file.header(frames_part >= 0 ? frames_part : 0);
        cube.attributes = detail::read_attributes(first);
        const Imath::Box2i dw = first.dataWindow();
        cube.width = dw.max.x - dw.min.x + 1;
        if (frames_part >= 0) {
            cube.height = int_attribute(cube.attributes, "femto:frame_height");
            cube.bins = int_attribute(cube.attributes, "femto:bins");
            // They describe this file's layout, not the render: outputs made from the cube
            // (a peak-time image, an unwarped cube) must not inherit them.
            std::erase_if(cube.attributes, [](const auto& a) {
                return a.first == "femto:frame_height" || a.first == "femto:layout";
            });
        } else {
            cube.height = dw.max.y - dw.min.y + 1;
            cube.bins = legacy_bins;
        }
        const uint64_t values =
            uint64_t(cube.width) * uint64_t(cube.height) * 3 * uint64_t(cube.bins);
        if (cube.width <= 0 || values > (uint64_t(1) << 34))
            throw std::runtime_error(fmt::format("its size {}x{}x{} is out of range", cube.width,
                                                 cube.height, cube.bins));
        // The parts' windows against that size, before it is allocated: a header's femto:bins
        // or femto:frame_height need not agree with the pixels its file holds.
        if (frames_part >= 0)
            checked_window(file.header(frames_part), cube.width, int64_t(cube.height) * cube.bins);
        if (depth_part >= 0) checked_window(file.header(depth_part), cube.width, cube.height);
        for (int p = 0; p < parts; ++p)  // what will be read, before it is allocated
            if (p == frames_part || p == depth_part || is_legacy_bin_part(file.header(p))) {
                if (const int tile_h = frames_tile_rows(file.header(p), cube.width);
                    p == frames_part && tile_h > 0) {
                    Imf::TiledInputPart tiles(file, p);
                    require_whole_tiles(tiles, file.header(p).dataWindow(), tile_h);
                    continue;
                }
                Imf::InputPart part(file, p);
                if (p == depth_part)
                    detail::require_whole_exr(part, file.header(p).dataWindow(), {"Z"});
                else
                    detail::require_whole_exr(part, file.header(p).dataWindow(), {"R", "G", "B"});
            }
        if (const std::string problem =
                memory_shortfall(double(values) * sizeof(float), "its pixels");
            !problem.empty())
            throw std::runtime_error(problem);
        assign_in_huge_pages(cube.data, values, 0.f);
        if (frames_part >= 0)
            read_frames_part(file, frames_part, cube);
        else
            for (int p = 0; p < parts; ++p)
                if (is_legacy_bin_part(file.header(p))) read_legacy_bin_part(file, p, cube);
        if (depth_part >= 0) read_depth_part(file, depth_part, cube);
    } catch (const SceneError&) {
        throw;
    } catch (const std::exception& e) {
        throw SceneError(fmt::format("cannot read transient EXR \"{}\": {}", path, e.what()));
    }
    return cube;
}

// The .npy format (version 1.0) is a 10-byte preamble, a Python-dict header padded to a
// multiple of 64 bytes, and the raw little-endian data; small enough that no library is needed.
namespace {

std::string npy_header(const std::vector<size_t>& shape) {
    std::string dims;
    for (size_t d : shape) dims += std::to_string(d) + ", ";
    if (shape.size() > 1)
        dims.erase(dims.size() - 2);  // "(3,)" keeps its comma for 1-D
    else if (!dims.empty())
        dims.erase(dims.size() - 1);
    std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + dims + "), }";
    const size_t total = 10 + header.size() + 1;
    header.append((64 - total % 64) % 64, ' ');
    header += '\n';
    const unsigned char magic[8] = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0};
    const uint16_t len = uint16_t(header.size());
    return std::string(reinterpret_cast<const char*>(magic), 8) + char(len & 0xff) +
           char(len >> 8) + header;
}

// Writes the header, then body(out) the data; atomic like every other writer.
void write_npy_file(const std::string& path, const std::vector<size_t>& shape,
                    const std::function<void(std::ofstream&)>& body) {
    const std::string tmp = temp_path_for(path);
    {
        errno = 0;
        std::ofstream out(tmp, std::ios::binary);
        int err = out ? 0 : errno;  // the first failure's reason; later calls overwrite errno
        if (out) out << npy_header(shape);
        if (out) body(out);
        if (!out && !err) err = errno;
        out.close();  // a full disk often shows only when the last buffer is flushed
        if (out.fail()) {
            if (!err) err = errno;
            std::error_code ec;
            fs::remove(tmp, ec);
            throw SceneError(fmt::format("cannot write \"{}\": {}", path,
                                         err ? std::strerror(err) : "write error"));
        }
    }
    commit(tmp, path);
}

size_t product(const std::vector<size_t>& shape, size_t from) {
    size_t n = 1;
    for (size_t i = from; i < shape.size(); ++i) n *= shape[i];
    return n;
}

}  // namespace

void write_npy_pixels(const std::string& path, const std::vector<size_t>& shape,
                      const std::function<void(size_t pixel, float* out)>& fill_pixel) {
    if (shape.size() < 2) throw std::invalid_argument("write_npy_pixels: shape needs 2 pixel axes");
    const size_t pixels = shape[0] * shape[1], per_pixel = product(shape, 2);
    write_npy_file(path, shape, [&](std::ofstream& out) {
        std::vector<float> buf(per_pixel);
        for (size_t p = 0; p < pixels && out; ++p) {
            fill_pixel(p, buf.data());
            out.write(reinterpret_cast<const char*>(buf.data()),
                      std::streamsize(per_pixel * sizeof(float)));
        }
    });
}

void write_npy(const std::string& path, const std::vector<size_t>& shape, const float* data,
               const float* pixel_scale) {
    if (pixel_scale && shape.size() >= 2) {
        const size_t per_pixel = product(shape, 2);
        write_npy_pixels(path, shape, [&](size_t p, float* out) {
            for (size_t k = 0; k < per_pixel; ++k)
                out[k] = data[p * per_pixel + k] * pixel_scale[p];
        });
        return;
    }
    write_npy_file(path, shape, [&](std::ofstream& out) {
        out.write(reinterpret_cast<const char*>(data),
                  std::streamsize(product(shape, 0) * sizeof(float)));
    });
}

std::vector<float> read_npy(const std::string& path, std::vector<size_t>& shape) {
    // InputFile refuses a FIFO or a device, which would block the reader or never end.
    InputFile in(path, SourceLocation{});
    char pre[10];
    if (in.read(pre, 10) != 10 || std::memcmp(pre, "\x93NUMPY", 6) != 0)
        throw SceneError(fmt::format("\"{}\" is not a .npy file", path));
    if (pre[6] != 1)
        throw SceneError(fmt::format("\"{}\": only .npy version 1.0 is supported", path));
    const size_t len = size_t(uint8_t(pre[8])) | (size_t(uint8_t(pre[9])) << 8);
    std::string header(len, '\0');
    if (in.read(header.data(), len) != len)
        throw SceneError(fmt::format("\"{}\" is truncated", path));
    if (header.find("'descr': '<f4'") == std::string::npos ||
        header.find("'fortran_order': False") == std::string::npos)
        throw SceneError(fmt::format("\"{}\": expected little-endian float32 in C order", path));
    const size_t open = header.find('(', header.find("'shape'")), close = header.find(')', open);
    if (open == std::string::npos || close == std::string::npos)
        throw SceneError(fmt::format("\"{}\": no shape in the header", path));
    shape.clear();
    size_t count = 1;
    std::string dims = header.substr(open + 1, close - open - 1);
    for (size_t pos = 0; pos < dims.size();) {
        const size_t comma = dims.find(',', pos);
        const std::string item =
            dims.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
        if (item.find_first_of("0123456789") != std::string::npos) {
            size_t d = 0;
            try {
                d = std::stoull(item);
            } catch (const std::exception&) {  // not a number, or beyond 64 bits
                throw SceneError(fmt::format("\"{}\": bad shape", path));
            }
            if (d == 0 || d > (size_t(1) << 32))
                throw SceneError(fmt::format("\"{}\": bad shape", path));
            shape.push_back(d);
            count *= d;
            if (count > (size_t(1) << 34)) throw SceneError(fmt::format("\"{}\": too large", path));
        }
        if (comma == std::string::npos) break;
        pos = comma + 1;
    }
    // Checked before allocating: a header may declare far more data than the file holds.
    if (count * sizeof(float) > in.size() - 10 - len)
        throw SceneError(fmt::format("\"{}\" is truncated", path));
    std::vector<float> data;
    assign_in_huge_pages(data, count, 0.f);
    if (in.read(data.data(), count * sizeof(float)) != count * sizeof(float))
        throw SceneError(fmt::format("\"{}\" is truncated", path));
    return data;
}

// ---- output sets --------------------------------------------------------------------------

namespace detail {

// The sets open on this thread, innermost last: commit_file hands a finished file to the set
// that holds its path instead of renaming it.
std::vector<OutputSet*>& OutputSetAccess::open_sets() {
    thread_local std::vector<OutputSet*> sets;
    return sets;
}

bool OutputSetAccess::hold(const std::string& tmp, const std::string& path) {
    auto& sets = open_sets();
    for (auto it = sets.rbegin(); it != sets.rend(); ++it)
        if ((*it)->hold(tmp, path)) return true;
    return false;
}

}  // namespace detail

OutputSet::OutputSet() { detail::OutputSetAccess::open_sets().push_back(this); }

void OutputSet::close() {
    if (!open_) return;
    auto& sets = detail::OutputSetAccess::open_sets();
    sets.erase(std::remove(sets.begin(), sets.end(), this), sets.end());
    open_ = false;
}

std::string OutputSet::add(const std::string& path) {
    files_.emplace_back(std::string(), path);
    return files_.back().second;
}

bool OutputSet::hold(const std::string& tmp, const std::string& path) {
    for (auto& [held, final_path] : files_)
        if (final_path == path && held.empty()) {
            held = tmp;
            return true;
        }
    return false;
}

std::vector<std::string> OutputSet::commit() {
    close();
    for (const auto& [tmp, path] : files_)
        if (tmp.empty()) throw SceneError(fmt::format("\"{}\" was never written", path));
    std::vector<std::string> done;
    for (auto& [tmp, path] : files_) {
        std::error_code ec;
        fs::rename(tmp, path, ec);
        if (ec) {
            const std::string replaced =
                done.empty() ? "none" : fmt::format("\"{}\"", fmt::join(done, "\", \""));
            throw SceneError(fmt::format("cannot write \"{}\": {} (outputs already replaced: {})",
                                         path, ec.message(), replaced));
        }
        tmp.clear();
        done.push_back(path);
    }
    return done;
}

OutputSet::~OutputSet() {
    close();
    for (const auto& [tmp, path] : files_) {
        std::error_code ec;
        if (!tmp.empty()) fs::remove(tmp, ec);  // not committed: the old outputs stay
    }
}

}  // namespace femto::io
