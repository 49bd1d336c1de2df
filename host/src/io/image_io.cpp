#include "femto/image_io.h"

#include <OpenColorIO/OpenColorIO.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenImageIO/imageio.h>
#include <dlfcn.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>

#include "femto/color.h"
#include "femto/error.h"
#include "femto/input_file.h"
#include "io/atomic_file.h"
#include "io/display.h"

namespace fs = std::filesystem;
namespace OCIO = OCIO_NAMESPACE;

namespace femto::io {

namespace detail {

std::string temp_path_for(const std::string& path) {
    static std::atomic<unsigned> counter{0};
    const fs::path p(path);
    return (p.parent_path() / fmt::format(".{}.tmp{}-{}{}", p.stem().string(), getpid(), counter++,
                                          p.extension().string()))
        .string();
}

void commit_file(const std::string& tmp, const std::string& path) {
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
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

}  // namespace detail

using detail::temp_path_for;

namespace {

void commit(const std::string& tmp, const std::string& path) { detail::commit_file(tmp, path); }

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

std::string ocio_config_path() {
    if (const char* env = std::getenv("FEMTO_OCIO_CONFIG"); env && *env) return env;
    std::string installed = exe_relative_config();
    if (!installed.empty()) return installed;
    return FEMTO_SOURCE_OCIO_CONFIG;
}

void write_exr_rgb(const std::string& path, int width, int height, const float* rgb,
                   const Attributes& attributes, const float* depth) {
    const std::string tmp = temp_path_for(path);
    try {
        Imf::Header header(width, height);
        header.compression() = Imf::ZIP_COMPRESSION;
        for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
        if (depth) header.channels().insert("Z", Imf::Channel(Imf::FLOAT));
        for (const auto& [k, v] : attributes) header.insert(k, Imf::StringAttribute(v));
        Imf::FrameBuffer fb;
        const size_t xs = 3 * sizeof(float), ys = xs * size_t(width);
        char* base = reinterpret_cast<char*>(const_cast<float*>(rgb));
        fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
        fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
        fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
        if (depth)
            fb.insert("Z",
                      Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(depth)),
                                 sizeof(float), sizeof(float) * size_t(width)));
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

void write_png_preview(const std::string& path, int width, int height, const float* rgb,
                       float exposure) {
    const size_t n = size_t(width) * size_t(height);
    std::vector<float> buf(rgb, rgb + 3 * n);
    const float scale = std::exp2(exposure);
    for (float& v : buf) v = std::isfinite(v) ? std::max(0.f, v * scale) : 0.f;
    OCIO::PackedImageDesc desc(buf.data(), width, height, 3);
    detail::display_processor()->apply(desc);
    std::vector<unsigned char> bytes(3 * n);
    for (size_t i = 0; i < bytes.size(); ++i)
        bytes[i] = static_cast<unsigned char>(std::lround(std::clamp(buf[i], 0.f, 1.f) * 255.f));
    const std::string tmp = temp_path_for(path);
    auto out = OIIO::ImageOutput::create(tmp);
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    if (!out || !out->open(tmp, spec) || !out->write_image(OIIO::TypeDesc::UINT8, bytes.data()) ||
        !out->close()) {
        const std::string err = out ? out->geterror() : OIIO::geterror();
        std::error_code ec;
        fs::remove(tmp, ec);
        throw SceneError(fmt::format("cannot write \"{}\": {}", path, err));
    }
    commit(tmp, path);
}

namespace {

constexpr int kMaxImageSide = 1 << 16;
constexpr int64_t kMaxImagePixels = int64_t(1) << 28;

// OpenEXR allocates scanline buffers for the width a header claims while opening the file,
// before OpenImageIO hands femto the spec: a corrupt header could ask for gigabytes. Its own
// limit makes such files fail at the header instead.
void limit_openexr_sizes() {
    static std::once_flag once;
    std::call_once(once, [] {
        Imf::Header::setMaxImageSize(kMaxImageSide, kMaxImageSide);
        Imf::Header::setMaxTileSize(kMaxImageSide, kMaxImageSide);
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

// OpenImageIO's error for `in` (or its global one), leaving no error pending: OpenImageIO
// prints unretrieved errors when the process exits, after femto's own message.
std::string take_oiio_error(const OIIO::ImageInput* in) {
    std::string error = in ? in->geterror() : std::string();
    const std::string global = OIIO::geterror();
    if (error.empty()) error = global;
    if (error.empty()) return "unknown error";
    // Several lines (one per library layer) make one message: femto's errors are one line.
    while (!error.empty() && error.back() == '\n') error.pop_back();
    for (size_t nl; (nl = error.find('\n')) != std::string::npos;) error.replace(nl, 1, "; ");
    return error;
}

// Reads all channels as float; returns "" or what went wrong.
std::string decode_image(const std::string& path, OIIO::ImageSpec& spec,
                         std::vector<float>& pixels) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) return take_oiio_error(nullptr);
    spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 ||
        int64_t(spec.width) * spec.height > kMaxImagePixels)
        return fmt::format("unsupported size {}x{}x{} (at most 2^28 pixels)", spec.width,
                           spec.height, spec.nchannels);
    pixels.resize(size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels));
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data()))
        return take_oiio_error(in.get());
    return {};
}

}  // namespace

std::vector<float> read_image_rgb(const std::string& path, int& width, int& height,
                                  bool srgb_8bit) {
    if (const std::string problem = input_file_problem(path); !problem.empty())
        throw SceneError(fmt::format("cannot read image \"{}\": {}", path, problem));
    limit_openexr_sizes();
    OIIO::ImageSpec spec;
    std::vector<float> pixels;
    HeldStderr held;
    const std::string error = decode_image(path, spec, pixels);
    held.release(error.empty());
    if (!error.empty()) throw SceneError(fmt::format("cannot read image \"{}\": {}", path, error));
    width = spec.width;
    height = spec.height;
    const int nc = spec.nchannels;
    const bool decode = srgb_8bit && (spec.format == OIIO::TypeDesc::UINT8 ||
                                      spec.format == OIIO::TypeDesc::UINT16);
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

#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfPartType.h>

#include <cstring>
#include <fstream>

namespace femto::io {

const std::string* Cube::attribute(const std::string& name) const {
    for (const auto& [k, v] : attributes)
        if (k == name) return &v;
    return nullptr;
}

namespace {
std::string part_name(int bin) { return fmt::format("t{:05}", bin); }
}  // namespace

void write_exr_cube(const std::string& path, int width, int height, int bins, const float* data,
                    const float* depth, const Attributes& attributes, const float* pixel_scale) {
    const std::string tmp = temp_path_for(path);
    try {
        std::vector<Imf::Header> headers;
        const int parts = bins + (depth ? 1 : 0);
        headers.reserve(size_t(parts));
        for (int p = 0; p < parts; ++p) {
            Imf::Header h(width, height);
            h.compression() = Imf::ZIPS_COMPRESSION;  // one-line buffers: a cube has a part per bin
            h.setName(p < bins ? part_name(p) : "depth");
            h.setType(Imf::SCANLINEIMAGE);
            if (p < bins)
                for (const char* c : {"R", "G", "B"})
                    h.channels().insert(c, Imf::Channel(Imf::FLOAT));
            else
                h.channels().insert("Z", Imf::Channel(Imf::FLOAT));
            for (const auto& [k, v] : attributes) h.insert(k, Imf::StringAttribute(v));
            headers.push_back(std::move(h));
        }
        Imf::MultiPartOutputFile file(tmp.c_str(), headers.data(), parts);
        size_t xs = size_t(bins) * 3 * sizeof(float), ys = xs * size_t(width);
        const size_t pixels = size_t(width) * size_t(height);
        std::vector<float> frame(pixel_scale ? pixels * 3 : 0);  // one scaled bin at a time
        if (pixel_scale) xs = 3 * sizeof(float), ys = xs * size_t(width);
        for (int p = 0; p < parts; ++p) {
            Imf::OutputPart part(file, p);
            Imf::FrameBuffer fb;
            if (p < bins) {
                const float* src = data + size_t(p) * 3;
                if (pixel_scale) {
                    for (size_t i = 0; i < pixels; ++i)
                        for (int c = 0; c < 3; ++c)
                            frame[3 * i + c] =
                                src[i * size_t(bins) * 3 + size_t(c)] * pixel_scale[i];
                    src = frame.data();
                }
                char* base = reinterpret_cast<char*>(const_cast<float*>(src));
                fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
                fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
                fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
            } else {
                char* base = reinterpret_cast<char*>(const_cast<float*>(depth));
                fb.insert("Z", Imf::Slice(Imf::FLOAT, base, sizeof(float),
                                          sizeof(float) * size_t(width)));
            }
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

Cube read_exr_cube(const std::string& path) {
    Cube cube;
    try {
        Imf::MultiPartInputFile file(path.c_str());
        const int parts = file.parts();
        const Imath::Box2i dw = file.header(0).dataWindow();
        cube.width = dw.max.x - dw.min.x + 1;
        cube.height = dw.max.y - dw.min.y + 1;
        for (auto it = file.header(0).begin(); it != file.header(0).end(); ++it)
            if (const auto* a = dynamic_cast<const Imf::StringAttribute*>(&it.attribute()))
                cube.attributes.emplace_back(it.name(), a->value());
        for (int p = 0; p < parts; ++p) {
            const std::string name = file.header(p).hasName() ? file.header(p).name() : "";
            if (name.size() == 6 && name[0] == 't') ++cube.bins;
        }
        if (cube.bins == 0)
            throw std::runtime_error(
                "it is not a femto transient cube (no parts named t00000, ...)");
        const size_t w = size_t(cube.width), h = size_t(cube.height), T = size_t(cube.bins);
        cube.data.assign(w * h * T * 3, 0.f);
        const size_t xs = T * 3 * sizeof(float), ys = xs * w;
        for (int p = 0; p < parts; ++p) {
            const Imf::Header& hd = file.header(p);
            const Imath::Box2i pw = hd.dataWindow();
            if (pw.max.x - pw.min.x + 1 != cube.width || pw.max.y - pw.min.y + 1 != cube.height)
                throw std::runtime_error("its parts have different sizes");
            const std::string name = hd.hasName() ? hd.name() : "";
            Imf::InputPart part(file, p);
            Imf::FrameBuffer fb;
            const ptrdiff_t origin =
                -(ptrdiff_t(pw.min.y) * ptrdiff_t(ys) + ptrdiff_t(pw.min.x) * ptrdiff_t(xs));
            if (name == "depth") {
                cube.depth.assign(w * h, -1.f);
                char* base =
                    reinterpret_cast<char*>(cube.depth.data()) -
                    (ptrdiff_t(pw.min.y) * ptrdiff_t(w) + pw.min.x) * ptrdiff_t(sizeof(float));
                fb.insert("Z", Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * w));
            } else if (name.size() == 6 && name[0] == 't') {
                const int bin = std::stoi(name.substr(1));
                if (bin < 0 || bin >= cube.bins)
                    throw std::runtime_error("a part name is out of range: " + name);
                char* base = reinterpret_cast<char*>(cube.data.data() + size_t(bin) * 3) + origin;
                fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
                fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
                fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
            } else {
                continue;
            }
            part.setFrameBuffer(fb);
            part.readPixels(pw.min.y, pw.max.y);
        }
    } catch (const SceneError&) {
        throw;
    } catch (const std::exception& e) {
        throw SceneError(fmt::format("cannot read transient EXR \"{}\": {}", path, e.what()));
    }
    return cube;
}

// The .npy format (version 1.0) is a 10-byte preamble, a Python-dict header padded to a
// multiple of 64 bytes, and the raw little-endian data; small enough that no library is needed.
void write_npy(const std::string& path, const std::vector<size_t>& shape, const float* data,
               const float* pixel_scale) {
    std::string dims;
    size_t count = 1;
    for (size_t d : shape) {
        dims += std::to_string(d) + ", ";
        count *= d;
    }
    if (shape.size() > 1)
        dims.erase(dims.size() - 2);  // "(3,)" keeps its comma for 1-D
    else if (!dims.empty())
        dims.erase(dims.size() - 1);
    std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + dims + "), }";
    const size_t total = 10 + header.size() + 1;
    header.append((64 - total % 64) % 64, ' ');
    header += '\n';
    const std::string tmp = temp_path_for(path);
    {
        std::ofstream out(tmp, std::ios::binary);
        const unsigned char magic[8] = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0};
        out.write(reinterpret_cast<const char*>(magic), 8);
        const uint16_t len = uint16_t(header.size());
        const char le[2] = {char(len & 0xff), char(len >> 8)};
        out.write(le, 2);
        out << header;
        if (pixel_scale && shape.size() >= 2 && shape[0] * shape[1] > 0) {
            const size_t pixels = shape[0] * shape[1], per_pixel = count / pixels;
            std::vector<float> buf(per_pixel);
            for (size_t i = 0; i < pixels && out; ++i) {
                for (size_t k = 0; k < per_pixel; ++k)
                    buf[k] = data[i * per_pixel + k] * pixel_scale[i];
                out.write(reinterpret_cast<const char*>(buf.data()),
                          std::streamsize(per_pixel * sizeof(float)));
            }
        } else {
            out.write(reinterpret_cast<const char*>(data), std::streamsize(count * sizeof(float)));
        }
        if (!out) {
            std::error_code ec;
            fs::remove(tmp, ec);
            throw SceneError(fmt::format("cannot write \"{}\"", path));
        }
    }
    commit(tmp, path);
}

std::vector<float> read_npy(const std::string& path, std::vector<size_t>& shape) {
    std::ifstream in(path, std::ios::binary);
    char pre[10];
    if (!in.read(pre, 10) || std::memcmp(pre, "\x93NUMPY", 6) != 0)
        throw SceneError(fmt::format("\"{}\" is not a .npy file", path));
    if (pre[6] != 1)
        throw SceneError(fmt::format("\"{}\": only .npy version 1.0 is supported", path));
    const size_t len = size_t(uint8_t(pre[8])) | (size_t(uint8_t(pre[9])) << 8);
    std::string header(len, '\0');
    if (!in.read(header.data(), std::streamsize(len)))
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
            const size_t d = std::stoull(item);
            if (d == 0 || d > (size_t(1) << 32))
                throw SceneError(fmt::format("\"{}\": bad shape", path));
            shape.push_back(d);
            count *= d;
            if (count > (size_t(1) << 34)) throw SceneError(fmt::format("\"{}\": too large", path));
        }
        if (comma == std::string::npos) break;
        pos = comma + 1;
    }
    std::vector<float> data(count);
    if (!in.read(reinterpret_cast<char*>(data.data()), std::streamsize(count * sizeof(float))))
        throw SceneError(fmt::format("\"{}\" is truncated", path));
    return data;
}

}  // namespace femto::io
