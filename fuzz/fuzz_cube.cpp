// libFuzzer harness: the bytes of a time-resolved cube as `femto viz` reads it
// (femto::viz::load_cube): a two-part OpenEXR cube of tiled frames and a depth part, a streak
// image (a single-part EXR), or a .npy. A cube it accepts then goes through what the viz
// commands compute from it (time grid, levels, frames, peak times, rainbow fusion, a streak
// slice, unwarping), since mutated headers reach those as odd sizes and attributes.
// Seeds: cubes written by femto's own writers (fuzz/make_cube_seeds.cpp) and the inputs of
// earlier findings (fuzz/regressions/cube/).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "femto/viz.h"
#include "fuzz_common.h"

namespace {

// Every picture the viz commands make, once (small cubes: the harness' inputs are a few kB).
void compute_pictures(const femto::io::Cube& cube) {
    using namespace femto;
    const TimeGrid grid = viz::time_grid(cube);
    const std::vector<uint8_t> emitters = viz::emitter_pixels(cube);
    const float level = viz::reference_level(cube);
    if (cube.bins > 0) {
        const std::vector<float> rgb = viz::frame(cube, cube.bins / 2);
        viz::tone_map(rgb.data(), rgb.size() / 3, level, 0.f, viz::Tone::Log);
    }
    viz::peak_time_image(cube, 2);
    if (grid.known) viz::peak_times(cube, grid);
    const std::vector<float> fused = viz::rainbow_fusion(cube);
    viz::reference_level(fused, emitters);
    if (cube.height > 0) viz::streak_slice(cube, cube.height - 1);
    if (grid.known && !cube.depth.empty()) viz::unwarp(cube, grid, true);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    // load_cube() reads a file with the .npy magic number, or named .npy, as a .npy and any
    // other as an EXR: an input is named .npy only when it has the magic, so that a mutated EXR
    // stays with the EXR readers.
    const bool npy =
        size >= 6 && std::string(reinterpret_cast<const char*>(data), 6) == "\x93NUMPY";
    const std::string path =
        femto::fuzz::write_scratch(npy ? "input.npy" : "input.exr", data, size);
    femto::io::Cube cube;
    femto::fuzz::run_file(
        path, [&] { cube = femto::viz::load_cube(path); }, [&] { compute_pictures(cube); });
    return 0;
}
