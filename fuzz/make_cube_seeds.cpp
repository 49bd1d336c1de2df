// Writes the cube harness' seeds (fuzz_cube.cpp) with femto's own writers, so that they are
// the files `femto viz` meets: OpenEXR cubes (tiled frames part, depth part; every compression;
// tiles in more than one row and column), a cube without depth, a streak image and .npy cubes
// of 1, 3 and 4 channels; and, through OpenEXR, a cube in the older layout of one scanline part
// per bin, which femto no longer writes but still reads. The values are mostly zero with a pulse
// per pixel, so that compressed files stay a few kB (libFuzzer's mutations are slow on large
// inputs).
//
//   femto_fuzz_cube_seeds OUT_DIR
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfMultiPartOutputFile.h>
#include <ImfOutputPart.h>
#include <ImfPartType.h>
#include <ImfStringAttribute.h>

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "femto/image_io.h"
#include "femto/viz.h"

namespace {

using femto::io::Cube;

// A cube whose pixel (x, y) holds a pulse arriving at bin (x + 2 y) % bins and a dimmer tail.
Cube pulse_cube(int width, int height, int bins, bool depth, femto::TimeFrame frame) {
    Cube cube;
    cube.width = width;
    cube.height = height;
    cube.bins = bins;
    cube.data.assign(size_t(width) * size_t(height) * size_t(bins) * 3, 0.f);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const int t0 = (x + 2 * y) % bins;
            float* p =
                cube.data.data() + (size_t(y) * size_t(width) + size_t(x)) * size_t(bins) * 3;
            for (int t = t0; t < std::min(bins, t0 + 3); ++t)
                for (int c = 0; c < 3; ++c)
                    p[3 * t + c] = std::ldexp(1.f, -(t - t0)) * float(c + 1);
        }
    if (depth) {
        cube.depth.resize(size_t(width) * size_t(height));
        for (size_t p = 0; p < cube.depth.size(); ++p)
            cube.depth[p] = p % 5 == 0 ? -1.f : 0.25f * float(p % 7);
    }
    femto::TimeGrid grid;
    grid.start = 0.5;
    grid.bin_width = 0.25;
    grid.bins = bins;
    grid.length_unit = "m";
    grid.frame = frame;
    femto::RenderInfo info;
    info.integrator = "transient_path";
    info.samples_per_pixel = info.samples_requested = 4;
    cube.attributes = femto::io::time_resolved_attributes(grid, info, "histogram");
    return cube;
}

void write_exr(const std::string& path, const Cube& cube,
               femto::io::ExrCubeOptions::Compression c) {
    femto::io::ExrCubeOptions options;
    options.compression = c;
    options.threads = 1;
    femto::io::write_exr_cube(path, cube.width, cube.height, cube.bins, cube.data.data(),
                              cube.depth.empty() ? nullptr : cube.depth.data(), cube.attributes,
                              nullptr, options);
}

// The layout before the tiled frames part: part t (named t00000, ...) is bin t's frame.
void write_one_part_per_bin(const std::string& path, const Cube& cube) {
    std::vector<Imf::Header> headers;
    for (int t = 0; t < cube.bins; ++t) {
        Imf::Header header(cube.width, cube.height);
        char name[16];
        std::snprintf(name, sizeof name, "t%05d", t);
        header.setName(name);
        header.setType(Imf::SCANLINEIMAGE);
        for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
        for (const auto& [key, value] : cube.attributes)
            header.insert(key, Imf::StringAttribute(value));
        headers.push_back(header);
    }
    Imf::MultiPartOutputFile file(path.c_str(), headers.data(), cube.bins);
    const size_t xs = size_t(cube.bins) * 3 * sizeof(float), ys = xs * size_t(cube.width);
    for (int t = 0; t < cube.bins; ++t) {
        Imf::OutputPart part(file, t);
        Imf::FrameBuffer fb;
        char* base = reinterpret_cast<char*>(const_cast<float*>(cube.data.data() + t * 3));
        for (int c = 0; c < 3; ++c)
            fb.insert(std::string(1, "RGB"[c]),
                      Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys));
        part.setFrameBuffer(fb);
        part.writePixels(cube.height);
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: femto_fuzz_cube_seeds OUT_DIR\n");
        return 2;
    }
    const std::filesystem::path out(argv[1]);
    try {
        std::filesystem::create_directories(out);
        using Compression = femto::io::ExrCubeOptions::Compression;
        const Cube small = pulse_cube(3, 2, 8, true, femto::TimeFrame::Camera);
        write_exr((out / "small-none.exr").string(), small, Compression::none);
        write_exr((out / "small-rle.exr").string(), small, Compression::rle);
        write_exr((out / "small-zips.exr").string(), small, Compression::zips);
        write_exr((out / "small-piz.exr").string(), small, Compression::piz);
        write_exr((out / "no-depth-zip.exr").string(),
                  pulse_cube(4, 3, 5, false, femto::TimeFrame::World), Compression::zip);
        // 300 pixels wide: tiles of 256 x 64 rows (write_exr_cube's tiling), so two tile
        // columns and, with 4 rows of 40 bins (160 strip rows), three tile rows.
        write_exr((out / "tiles-zip.exr").string(),
                  pulse_cube(300, 4, 40, true, femto::TimeFrame::Camera), Compression::zip);
        write_one_part_per_bin((out / "one-part-per-bin.exr").string(),
                               pulse_cube(2, 2, 3, false, femto::TimeFrame::Camera));
        femto::io::Attributes streak_attributes = small.attributes;
        streak_attributes.push_back({"femto:row", "1"});
        femto::viz::write_streak_exr((out / "streak.exr").string(), small, 1, streak_attributes);
        const Cube npy = pulse_cube(2, 3, 4, false, femto::TimeFrame::Camera);
        for (size_t channels : {size_t(1), size_t(3), size_t(4)}) {
            std::vector<float> values;
            for (size_t i = 0; i < npy.data.size() / 3; ++i)
                for (size_t c = 0; c < channels; ++c)
                    values.push_back(npy.data[3 * i + std::min<size_t>(c, 2)]);
            femto::io::write_npy(
                (out / ("cube-" + std::to_string(channels) + ".npy")).string(),
                {size_t(npy.height), size_t(npy.width), size_t(npy.bins), channels}, values.data());
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "femto_fuzz_cube_seeds: %s\n", e.what());
        return 1;
    }
    return 0;
}
