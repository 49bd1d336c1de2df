// Output files: the transient cube's EXR layout (stacked frames, any bin count, the older
// one-part-per-bin layout still read), typed header numbers, streamed .npy files, and
// OutputSet (a render's files appear together, or the previous ones stay).
#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "femto/error.h"
#include "femto/image_io.h"
#include "femto/testing/render.h"
#include "femto/viz.h"

namespace fs = std::filesystem;
using namespace femto;
using femto::testing::temp_dir;

namespace {

// A cube whose every value is distinct, so any misplaced value shows.
std::vector<float> numbered_cube(int w, int h, int bins) {
    std::vector<float> data(size_t(w) * size_t(h) * size_t(bins) * 3);
    for (size_t i = 0; i < data.size(); ++i) data[i] = float(i) * 0.25f + 1.f;
    return data;
}

float value(const std::vector<float>& cube, int w, int bins, int x, int y, int t, int c) {
    return cube[((size_t(y) * size_t(w) + size_t(x)) * size_t(bins) + size_t(t)) * 3 + size_t(c)];
}

std::string read_text(const fs::path& p) {
    std::ifstream in(p);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// Overwrites the start of the value of EXR header attribute `name` of type `type` (its
// `occurrence`-th, counting from 0: a multi-part file has one per part) with `value`.
void patch_attribute(std::string& bytes, const std::string& name, const std::string& type,
                     const std::string& value, int occurrence = 0) {
    const std::string key = name + '\0' + type + '\0';
    size_t at = bytes.find(key);
    for (int i = 0; i < occurrence && at != std::string::npos; ++i) at = bytes.find(key, at + 1);
    ASSERT_NE(at, std::string::npos) << name;
    bytes.replace(at + key.size() + 4, value.size(), value);  // past the 4-byte size
}

std::string le32(uint32_t v) {
    return std::string{char(v), char(v >> 8), char(v >> 16), char(v >> 24)};
}

// Writes a 4 x 3 pixel, 5-bin cube (with a depth part when `depth`) to `path`; returns the
// file's bytes, for tests that corrupt its header.
std::string write_small_cube(const std::string& path, bool depth = false) {
    const std::vector<float> values(4 * 3 * 5 * 3, 0.5f), depths(4 * 3, 1.f);
    io::write_exr_cube(path, 4, 3, 5, values.data(), depth ? depths.data() : nullptr,
                       {{"femto:bins", "5"}});
    return read_bytes(path);
}

// `read` throws a SceneError whose message holds `text`.
void expect_scene_error(const std::function<void()>& read, const std::string& text) {
    try {
        read();
        ADD_FAILURE() << "no error";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
}

// The process' peak resident memory (getrusage's ru_maxrss) and peak virtual memory (VmPeak),
// in kB. Buffers allocated and never touched show in the second only.
int64_t peak_resident_kb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_maxrss;
}
int64_t peak_virtual_kb() {
    std::ifstream status("/proc/self/status");
    for (std::string line; std::getline(status, line);)
        if (line.rfind("VmPeak:", 0) == 0) return std::stoll(line.substr(7));
    return -1;
}

}  // namespace

// Shapes that take each batch path of the writer: a band of rows of one frame (< 32 bins),
// a few whole frames (32..255), 16 frames with a remainder (300 = 18 x 16 + 12), one bin.
class CubeLayout : public ::testing::TestWithParam<std::tuple<int, int, int>> {};

TEST_P(CubeLayout, FramesAreStackedTopToBottomAndReadBack) {
    const auto [w, h, bins] = GetParam();
    const auto dir = temp_dir("cube-layout");
    const std::vector<float> data = numbered_cube(w, h, bins);
    std::vector<float> scale(size_t(w) * size_t(h)), depth(scale.size());
    for (size_t p = 0; p < scale.size(); ++p) {
        scale[p] = 1.f / float(p + 2);
        depth[p] = float(p) - 0.5f;
    }
    const std::string path = (dir / "c.exr").string();
    io::write_exr_cube(path, w, h, bins, data.data(), depth.data(),
                       {{"femto:bins", std::to_string(bins)}, {"femto:start", "0.05"}},
                       scale.data());
    // As any EXR reader sees it: the first part, W wide and H * bins tall, bin t at rows t*H...
    int strip_w = 0, strip_h = 0;
    const std::vector<float> strip = io::read_image_rgb(path, strip_w, strip_h, false);
    ASSERT_EQ(strip_w, w);
    ASSERT_EQ(strip_h, h * bins);
    for (int t = 0; t < bins; ++t)
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c)
                    ASSERT_EQ(strip[((size_t(t) * h + y) * w + x) * 3 + c],
                              value(data, w, bins, x, y, t, c) * scale[size_t(y) * w + x])
                        << "x " << x << " y " << y << " t " << t;
    // ... and as femto reads it back: the scaled cube, the depth, the attributes.
    const io::Cube cube = io::read_exr_cube(path);
    EXPECT_EQ(cube.width, w);
    EXPECT_EQ(cube.height, h);
    EXPECT_EQ(cube.bins, bins);
    for (size_t i = 0; i < data.size(); ++i)
        ASSERT_EQ(cube.data[i], data[i] * scale[i / (size_t(bins) * 3)]) << i;
    EXPECT_EQ(cube.depth, depth);
    ASSERT_NE(cube.attribute("femto:start"), nullptr);
    EXPECT_EQ(*cube.attribute("femto:start"), "0.05");
    EXPECT_EQ(cube.attribute("femto:frame_height"), nullptr) << "a layout attribute leaked";
}

INSTANTIATE_TEST_SUITE_P(Shapes, CubeLayout,
                         ::testing::Values(std::make_tuple(3, 2, 4), std::make_tuple(5, 3, 40),
                                           std::make_tuple(4, 3, 300), std::make_tuple(2, 2, 1),
                                           std::make_tuple(1, 7, 17)));

TEST(CubeLayout, ManyBinsOfATinyFilmRoundTrip) {
    // 2^16 bins of a 3x2 film: a strip of 131,072 rows (one part per bin would need ~1.4 GB
    // of OpenEXR state to write it).
    const int w = 3, h = 2, bins = 1 << 16;
    const auto dir = temp_dir("cube-many-bins");
    // An image read first (a texture of the scene) sets OpenEXR's size limits for the process;
    // they must leave a cube's tall strip of frames alone.
    const float pixel[3] = {1, 2, 3};
    io::write_exr_rgb((dir / "texture.exr").string(), 1, 1, pixel, {});
    int tw = 0, th = 0;
    EXPECT_EQ(io::read_image_rgb((dir / "texture.exr").string(), tw, th, false).size(), 3u);
    const std::vector<float> data = numbered_cube(w, h, bins);
    const std::string path = (dir / "c.exr").string();
    io::write_exr_cube(path, w, h, bins, data.data(), nullptr,
                       {{"femto:bins", std::to_string(bins)}});
    const io::Cube cube = io::read_exr_cube(path);
    EXPECT_EQ(cube.bins, bins);
    EXPECT_EQ(cube.data, data);
    EXPECT_TRUE(cube.depth.empty());
}

// A cube cut short lacks its last pixel block: refused (before its pixels are allocated, which
// cli.exr_truncated checks for images under a memory limit), with OpenEXR's reason.
TEST(CubeLayout, ACubeCutShortIsRefused) {
    const int w = 3, h = 2, bins = 4096;
    const auto dir = temp_dir("cube-cut");
    const std::vector<float> data = numbered_cube(w, h, bins);
    const std::string path = (dir / "c.exr").string();
    io::write_exr_cube(path, w, h, bins, data.data(), nullptr,
                       {{"femto:bins", std::to_string(bins)}});
    fs::resize_file(path, fs::file_size(path) - 100);
    try {
        io::read_exr_cube(path);
        FAIL() << "no error";
    } catch (const SceneError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("cannot read transient EXR"), std::string::npos) << what;
        EXPECT_NE(what.find("Early end of file"), std::string::npos) << what;
    }
}

TEST(CubeLayout, TheOlderOnePartPerBinLayoutIsStillRead) {
    const int w = 3, h = 2, bins = 3;
    const auto dir = temp_dir("cube-legacy");
    const std::vector<float> data = numbered_cube(w, h, bins);
    const std::string path = (dir / "old.exr").string();
    {
        std::vector<Imf::Header> headers;
        for (int t = 0; t < bins; ++t) {
            Imf::Header hd(w, h);
            hd.setName("t0000" + std::to_string(t));
            hd.setType(Imf::SCANLINEIMAGE);
            for (const char* c : {"R", "G", "B"}) hd.channels().insert(c, Imf::Channel(Imf::FLOAT));
            hd.insert("femto:start", Imf::StringAttribute("1.5"));
            headers.push_back(hd);
        }
        Imf::MultiPartOutputFile file(path.c_str(), headers.data(), bins);
        const size_t xs = size_t(bins) * 3 * sizeof(float), ys = xs * w;
        for (int t = 0; t < bins; ++t) {
            Imf::OutputPart part(file, t);
            Imf::FrameBuffer fb;
            char* base = reinterpret_cast<char*>(const_cast<float*>(data.data() + t * 3));
            for (int c = 0; c < 3; ++c)
                fb.insert(std::string(1, "RGB"[c]),
                          Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys));
            part.setFrameBuffer(fb);
            part.writePixels(h);
        }
    }
    const io::Cube cube = io::read_exr_cube(path);
    EXPECT_EQ(cube.bins, bins);
    EXPECT_EQ(cube.data, data);
    EXPECT_EQ(*cube.attribute("femto:start"), "1.5");
}

// EXR images are read through OpenEXR where they have half or float R, G and B channels (so
// that an EXR texture does not load OpenImageIO), through OpenImageIO otherwise; either way the
// pixels are the ones OpenImageIO reads (its channels 0-2, or 0 for one channel).
void write_test_exr(const std::string& path, Imath::Box2i window,
                    const std::vector<std::pair<std::string, Imf::PixelType>>& channels) {
    const int w = window.max.x - window.min.x + 1, h = window.max.y - window.min.y + 1;
    Imf::Header header(Imath::Box2i({0, 0}, {w - 1, h - 1}), window);
    for (const auto& [name, type] : channels) header.channels().insert(name, Imf::Channel(type));
    std::map<std::string, std::vector<float>> floats;
    std::map<std::string, std::vector<half>> halves;
    std::map<std::string, std::vector<uint32_t>> uints;
    Imf::FrameBuffer fb;
    size_t k = 0;
    for (const auto& [name, type] : channels) {
        const size_t n = size_t(w) * size_t(h);
        char* base = nullptr;
        size_t size = 0;
        if (type == Imf::FLOAT) {
            auto& v = floats[name];
            for (size_t i = 0; i < n; ++i) v.push_back(float(i) * 0.37f + float(k) * 100.f);
            base = reinterpret_cast<char*>(v.data()), size = sizeof(float);
        } else if (type == Imf::HALF) {
            auto& v = halves[name];
            for (size_t i = 0; i < n; ++i) v.push_back(half(float(i) * 0.25f + float(k) * 8.f));
            base = reinterpret_cast<char*>(v.data()), size = sizeof(half);
        } else {
            auto& v = uints[name];
            for (size_t i = 0; i < n; ++i) v.push_back(uint32_t(i * 1000 + k));
            base = reinterpret_cast<char*>(v.data()), size = sizeof(uint32_t);
        }
        fb.insert(name, Imf::Slice::Make(type, base, window.min, w, h, size, size * size_t(w)));
        ++k;
    }
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(h);
}

TEST(ImageRead, ExrPixelsAreThoseOpenImageIoReads) {
    const auto dir = temp_dir("image-read-exr");
    const Imath::Box2i shifted({3, -2}, {9, 4});
    const std::vector<std::pair<std::string, std::vector<std::pair<std::string, Imf::PixelType>>>>
        cases = {
            {"float-rgb", {{"R", Imf::FLOAT}, {"G", Imf::FLOAT}, {"B", Imf::FLOAT}}},
            {"half-bgra-z",
             {{"Z", Imf::FLOAT},
              {"B", Imf::HALF},
              {"G", Imf::HALF},
              {"R", Imf::HALF},
              {"A", Imf::HALF}}},
            {"gray", {{"Y", Imf::FLOAT}}},  // OpenImageIO's path: one channel
            {"uint-rgb", {{"R", Imf::UINT}, {"G", Imf::UINT}, {"B", Imf::UINT}}},
        };
    for (const auto& [name, channels] : cases) {
        SCOPED_TRACE(name);
        const std::string path = (dir / (name + ".exr")).string();
        write_test_exr(path, shifted, channels);
        int w = 0, h = 0;
        const std::vector<float> got = io::read_image_rgb(path, w, h, false);
        auto in = OIIO::ImageInput::open(path);
        ASSERT_TRUE(in);
        const OIIO::ImageSpec spec = in->spec();
        std::vector<float> all(size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels));
        ASSERT_TRUE(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data()));
        ASSERT_EQ(w, spec.width);
        ASSERT_EQ(h, spec.height);
        ASSERT_EQ(got.size(), size_t(w) * size_t(h) * 3);
        const size_t nc = size_t(spec.nchannels);
        for (size_t i = 0; i < size_t(w) * size_t(h); ++i)
            for (size_t c = 0; c < 3; ++c)
                ASSERT_EQ(got[3 * i + c], all[i * nc + (nc >= 3 ? c : 0)]) << "pixel " << i;
    }
}

// femto reports an EXR whose header OpenEXR refuses itself, without asking OpenImageIO (which
// reads EXRs through OpenEXR too). That must never refuse a file OpenImageIO reads: every
// truncation of a small EXR, and every single-byte change to its header, that femto refuses,
// OpenImageIO refuses as well.
// An EXR texture cut in half is refused before its pixels are allocated, whichever way its
// lines run (a cut decreasing-order file keeps its last row and loses its first). The file
// declares 8192 x 4096 RGB: 384 MiB as floats; the refusal must cost far less.
TEST(ImageRead, ACutExrIsRefusedBeforeItsPixelsAreAllocated) {
    const auto dir = temp_dir("image-read-cut-exr");
    const int W = 8192, H = 4096;
    for (const Imf::LineOrder order : {Imf::INCREASING_Y, Imf::DECREASING_Y}) {
        SCOPED_TRACE(order == Imf::INCREASING_Y ? "increasing" : "decreasing");
        const std::string whole = (dir / "whole.exr").string(), cut = (dir / "cut.exr").string();
        {
            Imf::Header header(W, H);
            header.compression() = Imf::RLE_COMPRESSION;  // quick to write
            header.lineOrder() = order;
            std::vector<float> row(static_cast<size_t>(W));  // every row alike: yStride 0
            Imf::FrameBuffer fb;
            for (const char* c : {"R", "G", "B"}) {
                header.channels().insert(c, Imf::Channel(Imf::FLOAT));
                fb.insert(c, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(row.data()),
                                        sizeof(float), 0));
            }
            Imf::OutputFile file(whole.c_str(), header);
            file.setFrameBuffer(fb);
            file.writePixels(H);
        }
        fs::copy_file(whole, cut, fs::copy_options::overwrite_existing);
        fs::resize_file(cut, fs::file_size(whole) / 2);
        const int64_t resident_before = peak_resident_kb();
        int w = 0, h = 0;
        expect_scene_error([&] { io::read_image_rgb(cut, w, h, false); }, "cut.exr");
        const int64_t grew = peak_resident_kb() - resident_before;
        EXPECT_LT(grew, 128L * 1024)  // kB
            << "peak memory grew by " << grew / 1024 << " MiB";
    }
}

// A text attribute declaring more bytes than the file holds is refused before OpenEXR reads
// it (OpenEXR 3.1 allocates the declared size first), in an image and in a cube.
TEST(ImageRead, AnAttributeLargerThanTheFileIsRefused) {
    const auto dir = temp_dir("image-read-huge-attribute");
    const float pixel[3] = {1, 2, 3};
    const std::string image = (dir / "image.exr").string(), cube = (dir / "cube.exr").string();
    io::write_exr_rgb(image, 1, 1, pixel, {{"femto:note", "abc"}});
    const std::vector<float> values(3 * 2 * 2 * 3, 0.5f);
    io::write_exr_cube(cube, 3, 2, 2, values.data(), nullptr,
                       {{"femto:bins", "2"}, {"femto:note", "abc"}});
    for (const std::string& path : {image, cube}) {
        SCOPED_TRACE(path);
        std::string bytes = read_bytes(path);
        const std::string key = std::string("femto:note") + '\0' + "string" + '\0';
        const size_t at = bytes.find(key);
        ASSERT_NE(at, std::string::npos);
        ASSERT_EQ(bytes.substr(at + key.size(), 4), std::string("\3\0\0\0", 4));
        bytes.replace(at + key.size(), 4, "\xff\xff\xff\x7f");  // 2^31 - 1 bytes
        write_bytes(path, bytes);
        expect_scene_error(
            [&] {
                int w = 0, h = 0;
                if (path == image)
                    io::read_image_rgb(path, w, h, false);
                else
                    io::read_exr_cube(path);
            },
            "attribute \"femto:note\" declares 2147483647 bytes");
    }
}

// OpenEXR allocates a buffer of one pixel block (a tile, or a compression's group of
// scanlines) per thread as it opens a file, sized by the header alone: a 538-byte file found by
// the cube fuzzer declared tiles of 16388 x 4096 pixels (805 MB a buffer). femto refuses such
// a header before OpenEXR opens the file.
TEST(ImageRead, PixelBlocksTooLargeToDecodeAreRefused) {
    const auto dir = temp_dir("image-read-huge-blocks");
    // A cube's tiled frames part with tiles of 16388 x 4096 float RGB pixels: 768 MiB a tile.
    const std::string cube = (dir / "cube.exr").string();
    std::string bytes = write_small_cube(cube);
    patch_attribute(bytes, "tiles", "tiledesc", le32(16388) + le32(4096));
    write_bytes(cube, bytes);
    expect_scene_error([&] { io::read_exr_cube(cube); },
                       "its tiles of 16388 x 4096 pixels would take 768 MiB each to decode");
    expect_scene_error([&] { viz::load_cube(cube); }, "768 MiB");

    // A scanline image of six float channels, 65536 pixels wide, DWAB-compressed (blocks of
    // 256 scanlines): 384 MiB a block.
    const std::string image = (dir / "image.exr").string();
    const float rgb[3] = {1, 2, 3}, depth = 4, extra[2] = {5, 6};
    io::write_exr_rgb(image, 1, 1, rgb, {}, &depth, {{"a", "b"}, extra});
    bytes = read_bytes(image);
    patch_attribute(bytes, "dataWindow", "box2i", le32(0) + le32(0) + le32(65535));
    patch_attribute(bytes, "compression", "compression", std::string(1, '\x09'));
    write_bytes(image, bytes);
    int w = 0, h = 0;
    expect_scene_error([&] { io::read_image_rgb(image, w, h, false); },
                       "its blocks of scanlines, 65536 pixels wide, would take 384 MiB each");
}

// OpenEXR's limit on widths (65536 pixels; limit_openexr_sizes()) holds for cubes as for
// images, also in a process that has read no image before (ctest runs each test alone): a cube
// whose depth part claimed 3,276,803 pixels a row made OpenEXR allocate 210 MB of scanline
// buffers (the cube fuzzer).
TEST(ImageRead, ACubeWiderThanOpenExrsLimitIsRefusedAtTheHeader) {
    const auto dir = temp_dir("image-read-wide-cube");
    const std::string cube = (dir / "cube.exr").string();
    std::string bytes = write_small_cube(cube, true);
    // The depth part's (the second) data window: x_max, after x_min and y_min.
    patch_attribute(bytes, "dataWindow", "box2i", le32(0) + le32(0) + le32(3'276'802), 1);
    write_bytes(cube, bytes);
    expect_scene_error([&] { viz::load_cube(cube); }, "exceeds the maximum width of 65536");
}

// The inputs the cube fuzzer found (fuzz/regressions/cube/, docs/fuzzing.md), each a header
// that made OpenEXR allocate hundreds of MB or overflowed a size: refused by a SceneError that
// names the file, before any large allocation (OpenEXR's untouched buffers do not show in the
// resident memory, but do in the peak virtual size). scripts/test.sh also runs them under
// ASan + UBSan.
TEST(ImageRead, TheCubeFuzzersFindingsAreRefused) {
    const std::filesystem::path dir =
        std::filesystem::path(FEMTO_SOURCE_DIR) / "fuzz" / "regressions" / "cube";
    const int64_t peak_before = peak_virtual_kb();
    ASSERT_GT(peak_before, 0);
    int files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        const std::string path = entry.path().string();
        SCOPED_TRACE(path);
        ++files;
        expect_scene_error([&] { viz::load_cube(path); }, path);
    }
    EXPECT_GE(files, 5);
    EXPECT_LT(peak_virtual_kb() - peak_before, 256 << 10) << "kB";
}

// Files the EXR fuzzer found (fuzz/regressions/exr/), which OpenImageIO reads as WebPs of
// 7425 x 13429 and 16129 x 14395 pixels whose decoding fails: femto zeroed a float buffer for
// all of the pixels first (1.6 GB for the 131-byte one; the render took 7 s and 2 GB of memory
// to exit with 2), later reserved it untouched (2.8 GB of address space for the 31-byte one,
// which the fuzzers count as running out of memory). Now a scanline image's first line is
// decoded before the buffer is allocated; what remains is OpenImageIO's own buffer of the
// declared size (400 and 930 MB), which it fills as it decodes the whole WebP at once.
TEST(ImageRead, AnImageDeclaringHugeSizeIsNotAllocatedBeforeDecoding) {
    const std::filesystem::path dir =
        std::filesystem::path(FEMTO_SOURCE_DIR) / "fuzz" / "regressions" / "exr";
    for (const char* name : {"webp-7425x13429-131-bytes.exr", "webp-16129x14395-31-bytes.exr"}) {
        const std::string path = (dir / name).string();
        SCOPED_TRACE(path);
        const int64_t resident_before = peak_resident_kb(), virtual_before = peak_virtual_kb();
        int w = 0, h = 0;
        expect_scene_error([&] { io::read_image_rgb(path, w, h); }, path);
        EXPECT_LT(peak_resident_kb() - resident_before, 1 << 20) << "kB of peak resident memory";
        EXPECT_LT(peak_virtual_kb() - virtual_before, 1 << 20) << "kB of peak virtual memory";
    }
}

// A cube's size comes from its femto:frame_height and femto:bins attributes; a header whose
// attributes disagree with the frames part's pixels is refused before the cube is allocated
// (it was allocated, and zeroed, first: here 3.6 GB for a file of a few kB).
TEST(CubeLayout, AttributesThatDisagreeWithThePixelsAreRefusedBeforeAllocating) {
    const auto dir = temp_dir("cube-disagreeing-bins");
    const std::string cube = (dir / "cube.exr").string();
    std::string bytes = write_small_cube(cube);
    patch_attribute(bytes, "femto:bins", "int", le32(100'000'000));
    write_bytes(cube, bytes);
    const int64_t resident_before = peak_resident_kb();
    expect_scene_error([&] { io::read_exr_cube(cube); }, "is not 4x300000000 pixels");
    EXPECT_LT(peak_resident_kb() - resident_before, 256 << 10) << "kB of peak resident memory";
}

TEST(ImageRead, AnExrFemtoRefusesOpenImageIoRefusesToo) {
    const auto dir = temp_dir("image-read-bad-exr");
    const std::string good = (dir / "good.exr").string();
    write_test_exr(good, Imath::Box2i({0, 0}, {5, 3}),
                   {{"R", Imf::HALF}, {"G", Imf::HALF}, {"B", Imf::HALF}});
    std::string bytes = read_bytes(good);
    const size_t last_attribute = bytes.find("screenWindowWidth");
    ASSERT_NE(last_attribute, std::string::npos);
    const size_t header_end = last_attribute + 40;  // past its value
    ASSERT_LT(header_end, bytes.size());
    std::vector<std::string> variants;
    for (size_t n = 4; n < bytes.size(); n += 3) variants.push_back(bytes.substr(0, n));
    for (size_t i = 4; i < header_end; ++i)
        for (const unsigned char x : {0x01, 0x80, 0xff}) {
            std::string changed = bytes;
            changed[i] = char(changed[i] ^ x);
            variants.push_back(changed);
        }
    const std::string path = (dir / "bad.exr").string();
    int refused = 0, by_femtos_reader = 0;
    for (size_t v = 0; v < variants.size(); ++v) {
        write_bytes(path, variants[v]);
        int w = 0, h = 0;
        try {
            io::read_image_rgb(path, w, h, false);
            continue;
        } catch (const SceneError& e) {
            ++refused;
            const std::string what = e.what();
            ASSERT_NE(what.find("cannot read image \"" + path + "\": "), std::string::npos) << what;
            by_femtos_reader += what.find("OpenEXR exception") == std::string::npos;
        }
        auto in = OIIO::ImageInput::open(path);
        if (!in) continue;
        const OIIO::ImageSpec spec = in->spec();
        std::vector<float> all(size_t(std::max(spec.width, 0)) * size_t(std::max(spec.height, 0)) *
                               size_t(std::max(spec.nchannels, 0)));
        EXPECT_FALSE(!all.empty() &&
                     in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data()))
            << "variant " << v << ": femto refused a file OpenImageIO reads";
        OIIO::geterror();
    }
    EXPECT_GT(refused, int(variants.size()) / 4);
    EXPECT_GT(by_femtos_reader, 0);  // refused by femto's reader, not OpenImageIO's
}

TEST(CubeLayout, HeaderNumbersAreTypedAndBigIntegersStayExact) {
    const auto dir = temp_dir("cube-attrs");
    const std::vector<float> data = numbered_cube(2, 1, 2);
    const std::string path = (dir / "c.exr").string();
    io::write_exr_cube(path, 2, 1, 2, data.data(), nullptr,
                       {{"femto:bins", "2"},
                        {"femto:start", "0.05"},
                        {"femto:seed", "18446744073709551615"},
                        {"femto:scene", "a.xml"}});
    auto in = OIIO::ImageInput::open(path);
    ASSERT_TRUE(in);
    const OIIO::ImageSpec& spec = in->spec();
    EXPECT_EQ(spec.getattributetype("femto:bins"), OIIO::TypeInt);
    EXPECT_EQ(spec.getattributetype("femto:start"), OIIO::TypeDesc(OIIO::TypeDesc::DOUBLE));
    EXPECT_EQ(spec.getattributetype("femto:seed"), OIIO::TypeString) << "a double would round it";
    EXPECT_EQ(spec.getattributetype("femto:scene"), OIIO::TypeString);
    in->close();
    const io::Cube cube = io::read_exr_cube(path);
    EXPECT_EQ(*cube.attribute("femto:start"), "0.05");
    EXPECT_EQ(*cube.attribute("femto:seed"), "18446744073709551615");
}

TEST(CubeLayout, CompressionsAllRoundTrip) {
    const auto dir = temp_dir("cube-compression");
    const std::vector<float> data = numbered_cube(5, 4, 64);
    for (const char* name : {"none", "rle", "zips", "zip", "piz"}) {
        io::ExrCubeOptions options;
        ASSERT_TRUE(io::parse_exr_compression(name, options.compression));
        options.threads = 2;
        const std::string path = (dir / (std::string(name) + ".exr")).string();
        io::write_exr_cube(path, 5, 4, 64, data.data(), nullptr, {{"femto:bins", "64"}}, nullptr,
                           options);
        EXPECT_EQ(io::read_exr_cube(path).data, data) << name;
    }
    io::ExrCubeOptions::Compression c;
    EXPECT_FALSE(io::parse_exr_compression("b44", c));
}

TEST(Npy, StreamedPixelsAndWriteErrorsSayWhy) {
    const auto dir = temp_dir("npy-stream");
    const std::string path = (dir / "v.npy").string();
    io::write_npy_pixels(path, {2, 3, 4}, [](size_t p, float* out) {
        for (int k = 0; k < 4; ++k) out[k] = float(p * 10 + k);
    });
    std::vector<size_t> shape;
    const std::vector<float> v = io::read_npy(path, shape);
    EXPECT_EQ(shape, (std::vector<size_t>{2, 3, 4}));
    EXPECT_EQ(v[5 * 4 + 3], 53.f);
    try {
        io::write_npy((dir / "no" / "such" / "x.npy").string(), {1}, v.data());
        ADD_FAILURE() << "no error";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("No such file"), std::string::npos) << e.what();
    }
}

// The message of reading a 128-byte .npy file (no data) whose header declares `shape`.
std::string npy_header_error(const fs::path& path, const std::string& shape) {
    std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': " + shape + ", }";
    header.resize(128 - 10 - 1, ' ');
    header += '\n';
    const std::string pre("\x93NUMPY\x01\x00", 8);
    write_text(path, pre + char(header.size()) + char(0) + header);
    std::vector<size_t> dims;
    try {
        io::read_npy(path.string(), dims);
    } catch (const SceneError& e) {
        return e.what();
    }
    ADD_FAILURE() << "no error for shape " << shape;
    return {};
}

// A dimension beyond 64 bits (std::stoull's out_of_range, which reached the CLI as an internal
// error, exit 1) is a bad shape like any other.
TEST(Npy, ADimensionBeyond64BitsIsABadShape) {
    const std::string error =
        npy_header_error(temp_dir("npy-huge-dim") / "huge.npy", "(99999999999999999999999, 2)");
    EXPECT_NE(error.find("bad shape"), std::string::npos) << error;
}

TEST(Npy, AShapeLargerThanTheFileIsRefusedBeforeAllocating) {
    // 2^16 x 2^16 x 2 floats (32 GiB, more than a test machine has) in a file of 128 bytes.
    const std::string error =
        npy_header_error(temp_dir("npy-short") / "big.npy", "(65536, 65536, 2)");
    EXPECT_NE(error.find("is truncated"), std::string::npos) << error;
}

TEST(OutputSet, FilesAppearTogetherOnCommit) {
    const auto dir = temp_dir("output-set");
    write_text(dir / "a.npy", "old a");
    const float one = 1.f;
    std::vector<std::string> files;
    {
        io::OutputSet set;
        io::write_npy(set.add((dir / "a.npy").string()), {1}, &one);
        io::write_npy(set.add((dir / "b.npy").string()), {1}, &one);
        EXPECT_EQ(read_text(dir / "a.npy"), "old a") << "replaced before commit";
        EXPECT_FALSE(fs::exists(dir / "b.npy"));
        files = set.commit();
    }
    EXPECT_EQ(files,
              (std::vector<std::string>{(dir / "a.npy").string(), (dir / "b.npy").string()}));
    std::vector<size_t> shape;
    EXPECT_EQ(io::read_npy((dir / "a.npy").string(), shape), std::vector<float>{1.f});
    EXPECT_EQ(io::read_npy((dir / "b.npy").string(), shape), std::vector<float>{1.f});
    EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 2);
}

TEST(OutputSet, AnAbandonedSetLeavesThePreviousFilesAndNoTemporaries) {
    const auto dir = temp_dir("output-set-abandon");
    write_text(dir / "a.npy", "old a");
    const float one = 1.f;
    try {
        io::OutputSet set;
        io::write_npy(set.add((dir / "a.npy").string()), {1}, &one);
        io::write_npy(set.add((dir / "no" / "b.npy").string()), {1}, &one);  // fails
        ADD_FAILURE() << "no error";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("cannot write \"" + (dir / "no" / "b.npy").string()),
                  std::string::npos)
            << "the message names the output, not its temporary: " << e.what();
    }
    EXPECT_EQ(read_text(dir / "a.npy"), "old a");
    EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(OutputSet, AFailedRenameNamesTheFilesAlreadyReplaced) {
    const auto dir = temp_dir("output-set-rename");
    fs::create_directories(dir / "b.npy" / "inside");  // a folder in the way
    const float one = 1.f;
    io::OutputSet set;
    io::write_npy(set.add((dir / "a.npy").string()), {1}, &one);
    io::write_npy(set.add((dir / "b.npy").string()), {1}, &one);
    try {
        set.commit();
        ADD_FAILURE() << "no error";
    } catch (const SceneError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("b.npy"), std::string::npos) << msg;
        EXPECT_NE(msg.find("already replaced: \"" + (dir / "a.npy").string()), std::string::npos)
            << msg;
    }
}
