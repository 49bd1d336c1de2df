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
#include <cstdlib>
#include <filesystem>
#include <mutex>

#include "femto/color.h"
#include "femto/error.h"

namespace fs = std::filesystem;
namespace OCIO = OCIO_NAMESPACE;

namespace femto::io {

namespace {

// A unique temporary name in the destination folder, keeping the extension (OIIO picks the
// format from it). Renamed into place only after a complete write.
std::string temp_path_for(const std::string& path) {
    static std::atomic<unsigned> counter{0};
    const fs::path p(path);
    return (p.parent_path() / fmt::format(".{}.tmp{}-{}{}", p.stem().string(), getpid(), counter++,
                                          p.extension().string()))
        .string();
}

void commit(const std::string& tmp, const std::string& path) {
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw SceneError(fmt::format("cannot write \"{}\": {}", path, ec.message()));
    }
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

}  // namespace

std::string ocio_config_path() {
    if (const char* env = std::getenv("FEMTO_OCIO_CONFIG"); env && *env) return env;
    std::string installed = exe_relative_config();
    if (!installed.empty()) return installed;
    return FEMTO_SOURCE_OCIO_CONFIG;
}

void write_exr_rgb(const std::string& path, int width, int height, const float* rgb,
                   const Attributes& attributes) {
    const std::string tmp = temp_path_for(path);
    try {
        Imf::Header header(width, height);
        header.compression() = Imf::ZIP_COMPRESSION;
        for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
        for (const auto& [k, v] : attributes) header.insert(k, Imf::StringAttribute(v));
        Imf::FrameBuffer fb;
        const size_t xs = 3 * sizeof(float), ys = xs * size_t(width);
        char* base = reinterpret_cast<char*>(const_cast<float*>(rgb));
        fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
        fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
        fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
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
    display_processor()->apply(desc);
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

std::vector<float> read_image_rgb(const std::string& path, int& width, int& height,
                                  bool srgb_8bit) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw SceneError(fmt::format("cannot read image \"{}\": {}", path, OIIO::geterror()));
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 ||
        int64_t(spec.width) * spec.height > (int64_t(1) << 28))
        throw SceneError(fmt::format("image \"{}\" has an unsupported size {}x{}x{}", path,
                                     spec.width, spec.height, spec.nchannels));
    width = spec.width;
    height = spec.height;
    const int nc = spec.nchannels;
    std::vector<float> pixels(size_t(width) * height * nc);
    if (!in->read_image(0, 0, 0, nc, OIIO::TypeDesc::FLOAT, pixels.data()))
        throw SceneError(fmt::format("cannot read image \"{}\": {}", path, in->geterror()));
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
