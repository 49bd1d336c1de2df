// libfemto_oiio.so: femto's uses of OpenImageIO (io/oiio_module.h says why they are apart).
#include "io/oiio_module.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

namespace {

using femto::io::detail::DecodedImage;

// OpenImageIO's error for `in` (or its global one), leaving no error pending: OpenImageIO
// prints unretrieved errors when the process exits, after femto's own message.
template <class File>
std::string take_error(const File* file) {
    std::string error = file ? file->geterror() : std::string();
    const std::string global = OIIO::geterror();
    if (error.empty()) error = global;
    if (error.empty()) return "unknown error";
    // Several lines (one per library layer) make one message: femto's errors are one line.
    while (!error.empty() && error.back() == '\n') error.pop_back();
    for (size_t nl; (nl = error.find('\n')) != std::string::npos;) error.replace(nl, 1, "; ");
    return error;
}

std::string decode(const std::string& path, int64_t max_pixels, DecodedImage& out) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) return take_error<OIIO::ImageInput>(nullptr);
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 ||
        int64_t(spec.width) * spec.height > max_pixels)
        return fmt::format("unsupported size {}x{}x{} (at most {} pixels)", spec.width, spec.height,
                           spec.nchannels, max_pixels);
    out.width = spec.width;
    out.height = spec.height;
    out.channels = spec.nchannels;
    out.integer_8_or_16 =
        spec.format == OIIO::TypeDesc::UINT8 || spec.format == OIIO::TypeDesc::UINT16;
    // Most corrupt files fail at their first pixels: a scanline image's first line is decoded
    // before the buffer for all of them is allocated. (A 31-byte WebP declaring 16129 x 14395
    // pixels had 2.8 GB reserved for it first, which the fuzzers count as running out of
    // memory; OpenImageIO then decodes the whole WebP on the first read and fails.)
    if (spec.tile_width == 0) {
        std::vector<float> line(size_t(spec.width) * size_t(spec.nchannels));
        if (!in->read_scanlines(0, 0, spec.y, spec.y + 1, spec.z, 0, spec.nchannels,
                                OIIO::TypeDesc::FLOAT, line.data()))
            return take_error(in.get());
    }
    out.pixels.reset(new float[size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels)]);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, out.pixels.get()))
        return take_error(in.get());
    return {};
}

std::string write_gif(const std::string& path, int width, int height,
                      const std::vector<std::vector<unsigned char>>& frames, int fps) {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) return take_error<OIIO::ImageOutput>(nullptr);
    if (!out->supports("multiimage")) return "this OpenImageIO cannot write multi-image GIFs";
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    const int rate[2] = {fps, 1};
    spec.attribute("FramesPerSecond", OIIO::TypeRational, rate);
    spec.attribute("oiio:Movie", 1);
    spec.attribute("oiio:LoopCount", 0);
    const std::vector<OIIO::ImageSpec> specs(frames.size(), spec);
    const bool append = out->supports("appendsubimage");
    bool ok = append ? out->open(path, spec) : out->open(path, int(specs.size()), specs.data());
    for (size_t f = 0; ok && f < frames.size(); ++f) {
        if (f > 0) ok = out->open(path, spec, OIIO::ImageOutput::AppendSubimage);
        ok = ok && out->write_image(OIIO::TypeDesc::UINT8, frames[f].data());
    }
    ok = ok && out->close();
    return ok ? std::string() : take_error(out.get());
}

constexpr femto::io::detail::OiioModule kModule{femto::io::detail::kOiioModuleVersion, decode,
                                                write_gif};

}  // namespace

extern "C" __attribute__((visibility("default"))) const femto::io::detail::OiioModule*
femto_oiio_module() {
    return &kModule;
}
