// `femto viz`: pictures from a time-resolved render (thesis ch. 4.3-4.6). The computations
// live in libfemto_io (femto/viz.h) so that the tests can call them; this file parses the
// command line, reads the cube and writes the files.
#include "viz.h"

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "femto/error.h"
#include "femto/viz.h"
#include "output_folder.h"

namespace fs = std::filesystem;

namespace femto::cli {

namespace {

struct VizOptions {
    std::string cube, output, exr, tone = "linear", to;
    std::optional<double> start, bin_width;
    std::optional<float> level;
    float exposure = 0.f;
    int row = -1, fps = 12, isochrones = 0;
    bool gif = false, mp4 = false, keep_window = false, quiet = false;
};

VizOptions g_opts;
CLI::App *g_viz = nullptr, *g_frames = nullptr, *g_peak = nullptr, *g_rainbow = nullptr,
         *g_streak = nullptr, *g_unwarp = nullptr;

void announce(const std::string& path) {
    if (!g_opts.quiet) fmt::print(stderr, "wrote {}\n", path);
}

// Creates the folder that will hold `path` (a file) and checks it is writable.
void prepare_file(const std::string& path, const char* what) {
    if (path.empty() || path.back() == '/')
        throw SceneError(fmt::format("{} \"{}\" must name a file", what, path));
    std::error_code ec;
    if (fs::is_directory(path, ec))
        throw SceneError(fmt::format("{} \"{}\" is a folder: name a file", what, path));
    prepare_output_folder(fs::path(path).parent_path());
}

void check_extension(const std::string& path, const char* ext, const char* option) {
    if (fs::path(path).extension() != ext)
        throw SceneError(fmt::format("{} \"{}\" must end in {}", option, path, ext));
}

io::Attributes time_attributes(const io::Cube& cube) {
    io::Attributes attrs;
    for (const auto& [k, v] : cube.attributes)
        if (k.rfind("femto:", 0) == 0) attrs.emplace_back(k, v);
    if (g_opts.start) attrs.emplace_back("femto:start", fmt::format("{}", *g_opts.start));
    if (g_opts.bin_width)
        attrs.emplace_back("femto:bin_width", fmt::format("{}", *g_opts.bin_width));
    attrs.emplace_back("femto:source", g_opts.cube);
    return attrs;
}

std::string find_on_path(const std::string& program) {
    const char* path = std::getenv("PATH");
    if (!path) return {};
    std::string paths = path;
    size_t pos = 0;
    while (pos <= paths.size()) {
        const size_t colon = std::min(paths.find(':', pos), paths.size());
        const fs::path candidate = fs::path(paths.substr(pos, colon - pos)) / program;
        if (access(candidate.c_str(), X_OK) == 0) return candidate.string();
        pos = colon + 1;
    }
    return {};
}

// Runs a program without a shell; returns its exit status (or -1).
int run_program(const std::vector<std::string>& args) {
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    const pid_t pid = fork();
    if (pid < 0) return -1;
    if (pid == 0) {
        execv(argv[0], argv.data());
        _exit(127);
    }
    int status = 0;
    if (waitpid(pid, &status, 0) < 0) return -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

int cmd_frames(const io::Cube& cube) {
    const viz::Tone tone = viz::parse_tone(g_opts.tone);
    const std::string dir = g_opts.output;
    prepare_output_folder(dir);
    std::error_code ec;
    auto frame_path = [&](int t) {
        return (fs::path(dir) / fmt::format("frame_{:05}.png", t)).string();
    };
    const std::string gif_path = (fs::path(dir) / "frames.gif").string();
    // A folder in the place of a file would stop the writing halfway: refused first.
    for (int t = 0; t <= cube.bins; ++t) {
        const std::string path = t < cube.bins ? frame_path(t) : gif_path;
        if (fs::is_directory(path, ec))
            throw SceneError(
                fmt::format("\"{}\" is a folder: femto viz frames writes a file there", path));
    }
    // One exposure for every frame, from the whole cube, so that frames are comparable.
    const float reference = g_opts.level ? *g_opts.level : viz::reference_level(cube);
    const size_t pixels = size_t(cube.width) * size_t(cube.height);
    std::vector<std::vector<float>> frames;
    io::OutputSet files;  // the frames (and the GIF) appear together or not at all
    for (int t = 0; t < cube.bins; ++t) {
        const std::vector<float> rgb = viz::frame(cube, t);
        std::vector<float> display =
            viz::tone_map(rgb.data(), pixels, reference, g_opts.exposure, tone);
        viz::write_png8(files.add(frame_path(t)), cube.width, cube.height, display);
        if (g_opts.gif) frames.push_back(std::move(display));
    }
    if (g_opts.gif)
        viz::write_gif(files.add(gif_path), cube.width, cube.height, frames, g_opts.fps);
    files.commit();
    if (!g_opts.quiet)
        fmt::print(stderr, "wrote {} frames {}/frame_00000.png ... (reference level {:.6g})\n",
                   cube.bins, dir, reference);
    if (g_opts.gif) announce(gif_path);
    if (g_opts.mp4) {
        const std::string ffmpeg = find_on_path("ffmpeg");
        if (ffmpeg.empty()) {
            fmt::print(stderr, "femto viz: ffmpeg is not on PATH; skipping the MP4\n");
        } else {
            const std::string path = (fs::path(dir) / "frames.mp4").string();
            const std::string tmp =
                (fs::path(dir) / fmt::format(".frames.tmp{}.mp4", getpid())).string();
            const int code = run_program(
                {ffmpeg, "-y", "-loglevel", "error", "-framerate", std::to_string(g_opts.fps), "-i",
                 (fs::path(dir) / "frame_%05d.png").string(), "-vf",
                 "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-pix_fmt", "yuv420p", tmp});
            if (code != 0) {
                fs::remove(tmp, ec);
                throw std::runtime_error(fmt::format("ffmpeg failed (exit code {})", code));
            }
            fs::rename(tmp, path, ec);
            if (ec) throw SceneError(fmt::format("cannot write \"{}\": {}", path, ec.message()));
            announce(path);
        }
    }
    return 0;
}

int cmd_peak_time(const io::Cube& cube, const TimeGrid& grid) {
    check_extension(g_opts.output, ".png", "-o");
    if (!g_opts.exr.empty()) {
        check_extension(g_opts.exr, ".exr", "--exr");
        if (!grid.known)
            throw SceneError(
                "--exr writes times, which need the cube's time axis: give --start "
                "and --bin-width for a .npy");
        prepare_file(g_opts.exr, "--exr");
    }
    prepare_file(g_opts.output, "-o");
    if (g_opts.isochrones < 0) throw SceneError("--isochrones must be >= 0");
    const std::vector<float> img =
        viz::peak_time_image(cube, g_opts.isochrones, g_opts.level, g_opts.exposure);
    io::OutputSet files;  // the PNG and the EXR appear together or not at all
    viz::write_png8(files.add(g_opts.output), cube.width, cube.height, img);
    if (!g_opts.exr.empty()) {
        const std::vector<float> times = viz::peak_times(cube, grid);
        io::Attributes attrs = time_attributes(cube);
        attrs.emplace_back("femto:content",
                           "peak time per pixel (bin centre, scene units); NaN where black");
        viz::write_exr_gray(files.add(g_opts.exr), cube.width, cube.height, times.data(), attrs);
    }
    for (const std::string& file : files.commit()) announce(file);
    return 0;
}

int cmd_rainbow(const io::Cube& cube) {
    const viz::Tone tone = viz::parse_tone(g_opts.tone);
    check_extension(g_opts.output, ".png", "-o");
    prepare_file(g_opts.output, "-o");
    if (!g_opts.exr.empty()) {
        check_extension(g_opts.exr, ".exr", "--exr");
        prepare_file(g_opts.exr, "--exr");
    }
    const std::vector<float> rgb = viz::rainbow_fusion(cube);
    const size_t pixels = size_t(cube.width) * size_t(cube.height);
    const float reference =
        g_opts.level ? *g_opts.level : viz::reference_level(rgb, viz::emitter_pixels(cube));
    io::OutputSet files;  // the PNG and the EXR appear together or not at all
    viz::write_png8(files.add(g_opts.output), cube.width, cube.height,
                    viz::tone_map(rgb.data(), pixels, reference, g_opts.exposure, tone));
    if (!g_opts.exr.empty()) {
        io::Attributes attrs = time_attributes(cube);
        attrs.emplace_back("femto:content", "rainbow fusion (thesis ch. 4.5)");
        io::write_exr_rgb(files.add(g_opts.exr), cube.width, cube.height, rgb.data(), attrs);
    }
    for (const std::string& file : files.commit()) announce(file);
    return 0;
}

// The streak slice's default level: every time row of a column that sees an emitter is skipped.
float streak_level(const io::Cube& cube, const std::vector<float>& slice) {
    const std::vector<uint8_t> emitter = viz::emitter_pixels(cube);
    std::vector<uint8_t> excluded(size_t(cube.width) * size_t(cube.bins));
    for (size_t t = 0; t < size_t(cube.bins); ++t)
        std::copy_n(&emitter[size_t(g_opts.row) * size_t(cube.width)], size_t(cube.width),
                    &excluded[t * size_t(cube.width)]);
    return viz::reference_level(slice, excluded);
}

int cmd_streak(const io::Cube& cube) {
    const viz::Tone tone = viz::parse_tone(g_opts.tone);
    check_extension(g_opts.output, ".png", "-o");
    const std::vector<float> img = viz::streak_slice(cube, g_opts.row);  // checks the row
    prepare_file(g_opts.output, "-o");
    if (!g_opts.exr.empty()) {
        check_extension(g_opts.exr, ".exr", "--exr");
        prepare_file(g_opts.exr, "--exr");
    }
    const size_t pixels = size_t(cube.width) * size_t(cube.bins);
    const float reference = g_opts.level ? *g_opts.level : streak_level(cube, img);
    io::OutputSet files;  // the PNG and the EXR appear together or not at all
    viz::write_png8(files.add(g_opts.output), cube.width, cube.bins,
                    viz::tone_map(img.data(), pixels, reference, g_opts.exposure, tone));
    if (!g_opts.exr.empty()) {
        // The streak film's format, with the row's depth in channel Z when the cube has it.
        io::Attributes attrs = time_attributes(cube);
        attrs.emplace_back("femto:row", std::to_string(g_opts.row));
        viz::write_streak_exr(files.add(g_opts.exr), cube, g_opts.row, std::move(attrs));
    }
    for (const std::string& file : files.commit()) announce(file);
    return 0;
}

int cmd_unwarp(const io::Cube& cube, const TimeGrid& grid) {
    check_extension(g_opts.output, ".exr", "-o");
    if (g_opts.to != "world" && g_opts.to != "camera")
        throw SceneError(fmt::format("--to must be world or camera, not \"{}\"", g_opts.to));
    prepare_file(g_opts.output, "-o");
    const viz::UnwarpResult r = viz::unwarp(cube, grid, g_opts.to == "world", g_opts.keep_window);
    if (r.dropped > 1e-6)
        fmt::print(stderr,
                   "femto viz: warning: {:.3g}% of the energy was shifted outside the time "
                   "window (--keep-window) and dropped\n",
                   100.0 * r.dropped);
    const bool streak = viz::is_streak(r.cube);
    if (streak)  // a streak image in, a streak image out (RGB + Z, same layout)
        viz::write_streak_exr(g_opts.output, r.cube, 0, r.cube.attributes);
    else
        io::write_exr_cube(g_opts.output, r.cube.width, r.cube.height, r.cube.bins,
                           r.cube.data.data(), r.cube.depth.data(), r.cube.attributes);
    if (!g_opts.quiet)
        fmt::print(stderr, "wrote {} ({}{} time, {} bins from {})\n", g_opts.output,
                   streak ? "streak image, " : "", g_opts.to, r.cube.bins,
                   *r.cube.attribute("femto:start"));
    return 0;
}

CLI::App* add_common(CLI::App* sub) {
    sub->add_option("cube", g_opts.cube,
                    "The cube: OUTBASE.exr of a transient film, or OUTBASE.npy ([H, W, T, C]); "
                    "unwarp also takes a streak image (OUTBASE_rowRRRR.exr)")
        ->required();
    sub->add_option("--start", g_opts.start,
                    "Start of the time window (scene units); needed for a .npy when times matter");
    sub->add_option("--bin-width", g_opts.bin_width,
                    "Bin width (scene units); needed for a .npy when times matter");
    sub->add_flag("-q,--quiet", g_opts.quiet, "Do not list the files written");
    return sub;
}

void add_level(CLI::App* sub) {
    sub->add_option("--level", g_opts.level,
                    "Reference level: the linear value shown as white (full brightness); default "
                    "the 99th percentile of the data over the pixels that do not see an emitter");
    sub->add_option("--exposure", g_opts.exposure,
                    "Exposure in stops, relative to the reference level");
}

void add_tone(CLI::App* sub) {
    sub->add_option("--tone", g_opts.tone,
                    "Tone curve: linear (sRGB display transform) or log (log(1 + 1000 x) / "
                    "log(1001), for the high dynamic range of transient data, ch. 4.5)")
        ->check(CLI::IsMember({"linear", "log"}));
    add_level(sub);
}

}  // namespace

CLI::App* add_viz_command(CLI::App& app) {
    g_viz = app.add_subcommand(
        "viz",
        "Make pictures from a transient render (thesis ch. 4.3-4.6): frames, peak-time, "
        "rainbow, streak, unwarp. See docs/viz.md.");
    g_viz->require_subcommand(1);

    g_frames = add_common(g_viz->add_subcommand(
        "frames",
        "One PNG per time bin (DIR/frame_00000.png, ...), all with ONE exposure chosen from the "
        "whole cube so that frames are comparable; optionally an animated GIF and an MP4"));
    g_frames->add_option("-o,--output", g_opts.output, "Output folder")->required();
    add_tone(g_frames);
    g_frames->add_flag("--gif", g_opts.gif, "Also write DIR/frames.gif (looping)");
    g_frames->add_flag("--mp4", g_opts.mp4,
                       "Also write DIR/frames.mp4 when ffmpeg is on PATH (skipped otherwise)");
    g_frames->add_option("--fps", g_opts.fps, "Frames per second of the GIF / MP4")
        ->check(CLI::Range(1, 100));

    g_peak = add_common(g_viz->add_subcommand(
        "peak-time",
        "Peak-time image (ch. 4.5): each pixel coloured by the time of its maximum radiance "
        "(red early ... blue late), brightness from the radiance around the peak"));
    g_peak->add_option("-o,--output", g_opts.output, "Output PNG")->required();
    g_peak->add_option("--exr", g_opts.exr,
                       "Also write the raw peak times (scene units, NaN where black) as EXR");
    g_peak->add_option("--isochrones", g_opts.isochrones,
                       "Thesis style: only every N-th bin contributes, so coloured isochrones are "
                       "separated by black (0 = continuous)");
    add_level(g_peak);

    g_rainbow = add_common(g_viz->add_subcommand(
        "rainbow",
        "Rainbow fusion (ch. 4.5): the sum of all frames, each tinted by the colour of its "
        "time (red early ... blue late)"));
    g_rainbow->add_option("-o,--output", g_opts.output, "Output PNG")->required();
    g_rainbow->add_option("--exr", g_opts.exr, "Also write the fused linear RGB image as EXR");
    add_tone(g_rainbow);

    g_streak = add_common(g_viz->add_subcommand(
        "streak",
        "Streak image (ch. 4.3): the x-t slice of the cube at one row, x to the right and "
        "time increasing downward"));
    g_streak->add_option("--row", g_opts.row, "The row (0 = top)")->required();
    g_streak->add_option("-o,--output", g_opts.output, "Output PNG")->required();
    g_streak->add_option("--exr", g_opts.exr,
                         "Also write the slice as EXR in the streak film's format (linear RGB, "
                         "plus the row's depth as channel Z when the cube has it)");
    add_tone(g_streak);

    g_unwarp = add_common(g_viz->add_subcommand(
        "unwarp",
        "Time unwarping (eq. 4.1): shift each pixel's time series by its sensor distance (the "
        "cube's depth part, a streak image's channel Z) to convert camera time to world time "
        "or back; writes a cube EXR, or a streak image for a streak image"));
    g_unwarp->add_option("-o,--output", g_opts.output, "Output cube or streak image (.exr)")
        ->required();
    g_unwarp->add_option("--to", g_opts.to, "Target time frame: world or camera")
        ->required()
        ->check(CLI::IsMember({"world", "camera"}));
    g_unwarp->add_flag("--keep-window", g_opts.keep_window,
                       "Keep the input's time window (energy shifted outside is dropped) instead "
                       "of growing it to hold everything");
    return g_viz;
}

int run_viz_command() {
    if (g_opts.level && !(*g_opts.level > 0 && std::isfinite(*g_opts.level)))
        throw SceneError(fmt::format("--level must be a positive number, got {}", *g_opts.level));
    if (!std::isfinite(g_opts.exposure))
        throw SceneError(
            fmt::format("--exposure must be a finite number of stops, got {}", g_opts.exposure));
    if (g_opts.start && !std::isfinite(*g_opts.start))
        throw SceneError(fmt::format("--start must be a finite time, got {}", *g_opts.start));
    const io::Cube cube = viz::load_cube(g_opts.cube);
    if (viz::is_streak(cube) && !g_unwarp->parsed()) {
        // Frames, peak-time and rainbow images of one row are a pixel tall, and a streak
        // image already is the streak slice of its row.
        const std::string* row = cube.attribute("femto:row");
        const CLI::App* sub = g_viz->get_subcommands().front();
        throw SceneError(fmt::format(
            "\"{}\" is a streak image (the x-t image of row {}), not an x-y-t cube: `femto viz "
            "{}` needs a cube (OUTBASE.exr of a transient film); of the viz subcommands only "
            "unwarp takes streak images",
            g_opts.cube, row ? *row : "?", sub->get_name()));
    }
    const TimeGrid grid = viz::time_grid(cube, g_opts.start, g_opts.bin_width);
    if (g_frames->parsed()) return cmd_frames(cube);
    if (g_peak->parsed()) return cmd_peak_time(cube, grid);
    if (g_rainbow->parsed()) return cmd_rainbow(cube);
    if (g_streak->parsed()) return cmd_streak(cube);
    if (g_unwarp->parsed()) return cmd_unwarp(cube, grid);
    throw SceneError("femto viz needs a subcommand: frames, peak-time, rainbow, streak, unwarp");
}

}  // namespace femto::cli
