// The run loop of `femto bench`: references (rendered once, cached by content hash), the runs
// interleaved variant by variant within each (budget, seed), one CSV row per finished run.
#include "bench/runner.h"

#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <thread>
#include <utility>

#include "bench/measures.h"
#include "bench/raw_rays.h"
#include "bench/report.h"
#include "femto/host.h"
#include "femto/image_io.h"
#include "femto/integrator.h"
#include "femto/sensor.h"
#include "femto/tfilter.h"
#include "util/strings.h"

namespace fs = std::filesystem;

namespace femto::bench {

namespace {

std::string read_bytes(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

LoadOptions load_options(const SceneSpec& scene, const Variant& variant,
                         const RunnerOptions& options) {
    LoadOptions lo;
    lo.defines = variant.defines;  // a variant's value wins over its scene's
    for (const auto& d : scene.defines)
        if (std::none_of(variant.defines.begin(), variant.defines.end(),
                         [&](const auto& v) { return v.first == d.first; }))
            lo.defines.push_back(d);
    lo.plugin_dirs = options.plugin_dirs;
    for (const auto& d : variant.plugin_dirs) lo.plugin_dirs.push_back(d);
    return lo;
}

// The film's cube without its data: its shape [H, W, T, 3] (T = 1 for a steady film) and
// time grid.
Cube film_shape(const Film& film) {
    Cube c;
    c.H = size_t(film.height()), c.W = size_t(film.width()), c.T = 1, c.C = 3;
    if (const auto* trf = dynamic_cast<const TimeResolvedFilm*>(&film)) {
        c.T = size_t(trf->grid().bins);
        c.start = trf->grid().start, c.bin_width = trf->grid().bin_width;
    }
    return c;
}

// Writes the film's result as STEM.npy and returns the cube's shape and time grid (no data): a
// time-resolved film's cube through its own writer, with its other outputs (as `femto render
// --npy` writes them), else the steady image as [H, W, 1, 3].
Cube write_film_npy(Scene& scene, const RenderOptions& ro, const RenderStats& stats,
                    const std::string& stem) {
    const Film& film = scene.sensor().film();
    Cube out = film_shape(film);
    fs::create_directories(fs::path(stem).parent_path());
    if (dynamic_cast<const TimeResolvedFilm*>(&film)) {
        RenderInfo info = make_render_info(scene, ro, stats);
        info.write_npy = true;
        film.write(stem, info);
        if (fs::exists(stem + ".npy")) return out;
    }
    // A film that writes no .npy of its own (a streak film): its steady image, one bin.
    out.T = 1;
    const std::vector<float> image = film.steady_image();
    io::write_npy(stem + ".npy", {out.H, out.W, 1, 3}, image.data());
    return out;
}

// Reads STEM.npy as written by write_film_npy() into `c` (whose time grid it keeps).
void read_film_npy(const std::string& stem, Cube& c) {
    std::vector<size_t> shape;
    c.data = io::read_npy(stem + ".npy", shape);
    if (shape.size() != 4) throw std::runtime_error("the film's .npy is not [H, W, T, C]");
    c.H = shape[0], c.W = shape[1], c.T = shape[2], c.C = shape[3];
}

// The film's cube [H, W, T, 3] (T = 1 for a steady film), through its own writer.
Cube film_cube(Scene& scene, const RenderOptions& ro, const RenderStats& stats,
               const fs::path& scratch) {
    Cube out = write_film_npy(scene, ro, stats, (scratch / "run").string());
    read_film_npy((scratch / "run").string(), out);
    fs::remove_all(scratch);
    return out;
}

Cube read_reference_file(const std::string& path) {
    Cube c;
    if (fs::path(path).extension() == ".npy") {
        std::vector<size_t> shape;
        c.data = io::read_npy(path, shape);
        if (shape.size() != 4)
            throw SceneError(
                fmt::format("reference \"{}\": a .npy reference must be [H, W, T, C]", path));
        c.H = shape[0], c.W = shape[1], c.T = shape[2], c.C = shape[3];
        return c;
    }
    try {  // a femto transient .exr, else any RGB image (steady)
        io::Cube cube = io::read_exr_cube(path);
        c.H = size_t(cube.height), c.W = size_t(cube.width), c.T = size_t(cube.bins), c.C = 3;
        c.data = std::move(cube.data);
        return c;
    } catch (const SceneError&) {
    }
    int w = 0, h = 0;
    c.data = io::read_image_rgb(path, w, h, true);  // an 8-bit image is sRGB-encoded
    c.H = size_t(h), c.W = size_t(w), c.T = 1, c.C = 3;
    return c;
}

// What a rendered reference depends on: the scene file, every file of the plugin folders in
// use (femto's own included), the defines, spp, seed and femto's version.
std::string reference_key(const Experiment& e, const SceneSpec& scene,
                          const RunnerOptions& options) {
    const Variant& v = *e.find_variant(e.reference.variant);
    const LoadOptions lo = load_options(scene, v, options);
    std::string text = read_bytes(scene.file);
    for (const auto& [k, val] : lo.defines) text += "\n-D" + k + "=" + val;
    text += fmt::format("\nspp {} seed {} femto {}", e.reference.spp, e.reference.seed, version());
    for (const std::string& dir : plugin_search_path(lo)) {
        std::vector<fs::path> files;
        for (const auto& f : fs::directory_iterator(dir))
            if (f.is_regular_file()) files.push_back(f.path());
        std::sort(files.begin(), files.end());
        for (const fs::path& f : files) text += "\n" + f.filename().string() + read_bytes(f);
    }
    return digest_hex(text);
}

struct Rendered {
    Cube cube;
    RenderStats stats;
    double cpu_seconds = NAN;  // process CPU time during the render
    double peak_mb = NAN;      // a child process's peak resident memory
    bool stopped = false;      // by the user: the run does not count
};

// This process's peak resident memory so far (VmHWM), in MB; NaN where /proc does not say.
double peak_resident_mb() {
    std::ifstream status("/proc/self/status");
    for (std::string line; std::getline(status, line);)
        if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // kB
    return NAN;
}

// Renders `lo`'s scene with `seed` at `spp` samples per pixel. Ctrl-C stops it at once (the
// run is then discarded: a render stopped within a pass has pixels with fewer samples). With
// `measure`, the film's cube is read back (through `scratch`); with a `child_stem` instead, the
// film's outputs are written there and only the cube's shape is kept.
// With a `group`, every process of a distributed study renders a share of the passes and only
// rank 0's result holds the cube.
Rendered render_run(const std::string& file, const LoadOptions& lo, uint64_t seed, uint32_t spp,
                    int threads, const RunnerOptions& options, const fs::path& scratch,
                    bool measure = true, const std::string& child_stem = {},
                    StudyGroup* group = nullptr) {
    auto scene = load_scene(file, lo);
    std::atomic<bool> stop{false};
    RenderOptions ro;
    if (group) ro.group = &group->everyone();
    ro.seed = seed;
    ro.threads = threads;
    ro.progress = false;
    ro.scene_file = file;
    ro.spp = spp;
    ro.stop = &stop;
    std::mutex m;
    std::condition_variable cv;
    bool done = false;
    std::thread watcher([&] {  // forwards the user's Ctrl-C to this render
        std::unique_lock<std::mutex> lock(m);
        while (!done && !(options.stop && options.stop->load()))
            cv.wait_for(lock, std::chrono::milliseconds(20));
        if (!done) stop.store(true);
    });
    auto finish_watcher = [&] {
        {
            std::lock_guard<std::mutex> lock(m);
            done = true;
        }
        cv.notify_all();
        watcher.join();
    };
    Rendered r;
    const double cpu_before = process_cpu_seconds();
    try {
        r.stats = render(*scene, ro);
    } catch (...) {
        finish_watcher();
        throw;
    }
    r.cpu_seconds = process_cpu_seconds() - cpu_before;
    finish_watcher();
    if (group) {
        std::vector<Accumulator> totals = scene->sensor().film().accumulators();
        for (const Accumulator& a : scene->integrator().accumulators()) totals.push_back(a);
        group->combine(totals);
        r.stopped = r.stats.interrupted;  // the same in every process
        if (group->rank() != 0) return r;
    } else {
        r.stopped = r.stats.interrupted || (options.stop && options.stop->load());
    }
    if (!r.stopped && !child_stem.empty())
        r.cube = write_film_npy(*scene, ro, r.stats, child_stem);
    else if (!r.stopped && measure)
        r.cube = film_cube(*scene, ro, r.stats, scratch);
    return r;
}

// A time budget becomes the sample count that fills it: a calibration render of a few samples
// (another seed; not recorded) gives the time per sample. Stopping a render at the budget's
// time instead would leave the pixels after the stop with fewer samples than the rest.
// Returns 0 when the user stopped it.
uint32_t spp_for_seconds(const std::string& file, const LoadOptions& lo, uint64_t seed,
                         double seconds, int threads, const RunnerOptions& options,
                         const fs::path& scratch) {
    constexpr uint32_t kCalibrationSpp = 4;
    const Rendered c = render_run(file, lo, seed ^ 0x5bd1e995ull, kCalibrationSpp, threads, options,
                                  scratch, false);
    if (c.stopped) return 0;
    const double per_sample = std::max(c.stats.seconds, 1e-9) / double(kCalibrationSpp);
    return uint32_t(std::clamp(std::floor(seconds / per_sample), 1.0, double(1u << 30)));
}

// ---- runs in child processes ------------------------------------------------------------------

// Renders one run as `femto bench-run` in a child process: its peak memory is then its own,
// not this process's history. The child reads it itself (VmHWM): wait4's ru_maxrss would not
// do, since Linux carries the spawning process's peak over into the child's at exec. The child
// writes the cube and its stats into `scratch`; Ctrl-C reaches it directly (same process group),
// SIGTERM is forwarded.
Rendered render_in_child(const std::string& file, const LoadOptions& lo, uint64_t seed,
                         uint32_t spp, int threads, const RunnerOptions& options,
                         const fs::path& scratch) {
    if (options.executable.empty())
        throw SceneError("<isolation value=\"process\"/>: the femto program to run is not known");
    fs::create_directories(scratch);
    const std::string stem = (scratch / "child").string();
    std::vector<std::string> args{options.executable,
                                  "bench-run",
                                  "--scene",
                                  file,
                                  "--out",
                                  stem,
                                  "--seed",
                                  std::to_string(seed),
                                  "--spp",
                                  std::to_string(spp),
                                  "--threads",
                                  std::to_string(threads)};
    for (const auto& [k, v] : lo.defines) args.insert(args.end(), {"-D", k + "=" + v});
    for (const std::string& d : lo.plugin_dirs) args.insert(args.end(), {"--plugin-dir", d});
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    if (posix_spawn(&pid, options.executable.c_str(), nullptr, nullptr, argv.data(), environ) != 0)
        throw SceneError(
            fmt::format("cannot run \"{}\" for a run in a child process", options.executable));
    int status = 0;
    bool forwarded = false;
    for (pid_t waited = 0; waited != pid;) {
        waited = waitpid(pid, &status, WNOHANG);
        if (waited < 0 && errno != EINTR)  // the child is gone without a status: never wait on
            throw SceneError(
                fmt::format("lost the run's child process ({})", std::strerror(errno)));
        if (options.stop && options.stop->load() && !forwarded) {
            kill(pid, SIGTERM);
            forwarded = true;
        }
        if (waited != pid) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    Rendered r;
    r.stopped =
        (options.stop && options.stop->load()) || (WIFEXITED(status) && WEXITSTATUS(status) == 130);
    if (r.stopped) {
        fs::remove_all(scratch);
        return r;
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        throw SceneError(fmt::format(
            "a run in a child process ({} bench-run --scene {} --seed {} --spp {}) failed with {} "
            "{}; its message is above",
            options.executable, file, seed, spp, WIFEXITED(status) ? "exit code" : "signal",
            WIFEXITED(status) ? WEXITSTATUS(status) : WTERMSIG(status)));
    std::ifstream stats(stem + ".stats");
    stats >> r.stats.seconds >> r.stats.rays >> r.stats.spp_done >> r.stats.camera_samples >>
        r.cpu_seconds >> r.cube.start >> r.cube.bin_width >> r.peak_mb;
    if (!stats)
        throw SceneError(fmt::format("a run in a child process left no readable result in {}",
                                     scratch.string()));
    read_film_npy(stem, r.cube);
    fs::remove_all(scratch);
    return r;
}

constexpr size_t kFixedColumns = 15;  // the columns before the windows

std::string csv_header(const Experiment& e) {
    std::string h =
        "scene,variant,budget,seed,spp,samples,seconds,cores_used,rays,peak_mb,relmse,pixel_"
        "relmse,frame_relmse,energy,relmse_raw";
    for (const Window& w : e.windows) h += ",window:" + w.name;
    for (const PixelSpec& p : e.pixels) h += ",pixel:" + p.name;
    return h;
}

std::string number_text(double v) { return std::isfinite(v) ? fmt::format("{:.9g}", v) : "nan"; }

// A finished run's lines of results.csv, frames.csv and profiles.csv (the last two empty
// without a reference), kept as text so that a worker of a distributed study can hand them to
// rank 0, which alone writes files. `progress` is its line for the terminal.
struct RunLines {
    std::string row, frames, profiles, progress;

    // One message: the four parts separated by the ASCII record separator (never in a CSV).
    std::string joined() const {
        return row + '\x1e' + frames + '\x1e' + profiles + '\x1e' + progress;
    }
    static RunLines split(const std::string& text) {
        RunLines l;
        std::string* parts[] = {&l.row, &l.frames, &l.profiles, &l.progress};
        size_t start = 0;
        for (std::string* part : parts) {
            const size_t end = std::min(text.find('\x1e', start), text.size());
            *part = text.substr(start, end - start);
            start = end + 1;
        }
        return l;
    }
};

std::string row_line(const RunRow& r) {
    std::ostringstream line;
    line << r.scene << "," << r.variant << "," << r.budget << "," << r.seed << "," << r.spp << ","
         << r.samples << "," << number_text(r.seconds) << "," << number_text(r.cores_used) << ","
         << r.rays << "," << number_text(r.peak_mb) << "," << number_text(r.rel_mse) << ","
         << number_text(r.pixel_rel_mse) << "," << number_text(r.frame_rel_mse) << ","
         << number_text(r.energy) << "," << number_text(r.rel_mse_raw);
    for (double w : r.windows) line << "," << number_text(w);
    for (double p : r.pixels) line << "," << number_text(p);
    line << "\n";
    return line.str();
}

// Appends `text` to `file` with one write (a kill leaves at most a last line without its
// newline, which read_results() drops), after `header` when the file is new or empty.
void append_lines(const fs::path& file, const std::string& header, const std::string& text) {
    if (text.empty()) return;
    const bool fresh = !fs::exists(file) || fs::file_size(file) == 0;
    std::ofstream out(file, std::ios::app);
    out << (fresh ? header + "\n" : std::string()) << text;
    out.flush();
    if (!out) throw SceneError(fmt::format("cannot write \"{}\"", file.string()));
}

// The row first: the run counts as done once it is there, and the per-frame and per-pixel lines
// follow it (a kill between leaves them short, never doubled by the re-run).
void append_run(const fs::path& dir, const Experiment& e, const RunLines& lines) {
    append_lines(dir / "results.csv", csv_header(e), lines.row);
    append_lines(dir / "frames.csv", "scene,variant,budget,seed,frame,relmse", lines.frames);
    append_lines(dir / "profiles.csv", "scene,variant,budget,seed,pixel,frame,time,value",
                 lines.profiles);
}

std::string frame_lines(const RunRow& r, const std::vector<double>& frames) {
    std::ostringstream out;
    for (size_t t = 0; t < frames.size(); ++t)
        out << r.scene << "," << r.variant << "," << r.budget << "," << r.seed << "," << t << ","
            << number_text(frames[t]) << "\n";
    return out.str();
}

// Pixel p's time profile of a run, for profiles.csv (time = the bin's centre).
std::string profile_lines(const RunRow& r, const PixelSpec& p, const Cube& c) {
    std::ostringstream out;
    const std::vector<double> profile = pixel_profile(c, p.x, p.y);
    for (size_t t = 0; t < profile.size(); ++t)
        out << r.scene << "," << r.variant << "," << r.budget << "," << r.seed << "," << p.name
            << "," << t << "," << number_text(c.start + (double(t) + 0.5) * c.bin_width) << ","
            << number_text(profile[t]) << "\n";
    return out.str();
}

// The reference's profiles of the experiment's pixels, with their standard deviation where the
// reference's variance is known: reference_profiles_SCENE.csv (rewritten each session). A pixel
// outside the film is an error at its <pixel>.
void write_reference_profiles(const Experiment& e, const SceneSpec& scene, const Cube& ref,
                              const fs::path& dir) {
    if (e.pixels.empty()) return;
    std::ofstream out(dir / ("reference_profiles_" + scene.name + ".csv"));
    out << "pixel,frame,value,stddev\n";
    for (const PixelSpec& p : e.pixels) {
        if (p.x < 0 || p.y < 0 || size_t(p.x) >= ref.W || size_t(p.y) >= ref.H)
            throw SceneError(p.location, fmt::format("pixel ({}, {}) is outside scene \"{}\"'s "
                                                     "{} x {} film",
                                                     p.x, p.y, scene.name, ref.W, ref.H));
        const std::vector<double> profile = pixel_profile(ref, p.x, p.y);
        for (size_t t = 0; t < profile.size(); ++t) {
            double var = 0;  // of the channels' mean
            if (!ref.variance.empty())
                for (size_t c = 0; c < ref.C; ++c)
                    var += ref.variance[((size_t(p.y) * ref.W + size_t(p.x)) * ref.T + t) * ref.C +
                                        c] /
                           double(ref.C * ref.C);
            out << p.name << "," << t << "," << number_text(profile[t]) << ","
                << (ref.variance.empty() ? std::string("nan") : number_text(std::sqrt(var)))
                << "\n";
        }
    }
}

// Each scene's reference key: reference_key() for a rendered reference, the digest of the
// file's bytes for a reference file. Computed once per session (it reads every plugin's bytes).
std::vector<std::string> reference_keys(const Experiment& e, const RunnerOptions& options) {
    std::vector<std::string> keys;
    for (const SceneSpec& scene : e.scenes)
        keys.push_back(!e.has_reference() ? std::string("none")
                       : e.reference.file.empty()
                           ? reference_key(e, e.reference_scene(scene), options)
                           : digest_hex(read_bytes(e.reference.file)));
    return keys;
}

// What the rows of a results folder depend on besides the experiment: the threads, the
// command line's plugin folders, each scene's file and its reference key (a rendered
// reference's covers femto's version and the plugins' bytes).
std::string setup_digest(const Experiment& e, const RunnerOptions& options, int threads,
                         const std::vector<std::string>& reference_keys) {
    std::string text = e.digest + fmt::format("\nthreads {}", threads);
    for (const std::string& d : options.plugin_dirs) text += "\nplugin_dir " + d;
    for (size_t i = 0; i < e.scenes.size(); ++i)
        text += "\n" + digest_hex(read_bytes(e.scenes[i].file)) + "\n" + reference_keys[i];
    return digest_hex(text);
}

// The output folder, checked against the setup that wrote its rows: rows measured with another
// experiment (seeds and budgets aside), scene, reference, plugins or thread count must not mix.
void prepare_out_dir(const std::string& setup, const fs::path& dir) {
    std::error_code ec;
    fs::create_directories(dir / "cache", ec);
    if (ec || access(dir.c_str(), W_OK) != 0)
        throw SceneError(fmt::format("cannot write into the output folder \"{}\"", dir.string()));
    // The study's own files must be files (or not exist yet): a folder in their place would
    // fail only when a run ends, after its time was spent.
    for (const char* name : {"results.csv", "frames.csv", "profiles.csv", "experiment.digest",
                             "report.md", "plot.svg"})
        if (fs::exists(dir / name, ec) && !fs::is_regular_file(dir / name, ec))
            throw SceneError(fmt::format("\"{}\" is not a file: the study writes its {} there",
                                         (dir / name).string(), name));
    const fs::path digest = dir / "experiment.digest";
    if (fs::exists(dir / "results.csv") && fs::exists(digest)) {
        std::string old = read_bytes(digest);
        while (!old.empty() && (old.back() == '\n' || old.back() == ' ')) old.pop_back();
        if (old != setup)
            throw SceneError(fmt::format(
                "\"{}\" holds rows measured under another setup (the experiment apart from its "
                "seeds and budgets, a scene file, the reference, the plugins or the thread count "
                "changed since): give another -o folder, or delete its results.csv to start over",
                dir.string()));
    }
    std::ofstream out(digest);
    if (!(out << setup << "\n").flush())
        throw SceneError(fmt::format("cannot write \"{}\"", digest.string()));
}

std::optional<Cube> render_reference(const Experiment& e, const SceneSpec& scene,
                                     const RunnerOptions& options, int threads,
                                     const fs::path& dir);

// Where a run's film writes its cube for the study to read: one folder per process of a
// distributed study, whose workers on one machine may share the results folder.
fs::path scratch_folder(const fs::path& dir, const RunnerOptions& options) {
    return options.group ? dir / fmt::format("scratch-{}", options.group->rank()) : dir / "scratch";
}

void write_reference_cache(const Cube& r, const std::string& mean_file,
                           const std::string& variance_file) {
    const std::vector<size_t> shape{r.H, r.W, r.T, r.C};
    // write_npy writes atomically; the mean last, since the cache is read only when both exist.
    io::write_npy(variance_file, shape, r.variance.data());
    io::write_npy(mean_file, shape, r.data.data());
}

// Rank 0's cube (shape, time grid, values and variance) to every process of a study.
void share_cube(StudyGroup& group, Cube& c) {
    std::string shape =
        fmt::format("{} {} {} {} {:.17g} {:.17g}", c.H, c.W, c.T, c.C, c.start, c.bin_width);
    group.broadcast(shape);
    std::istringstream(shape) >> c.H >> c.W >> c.T >> c.C >> c.start >> c.bin_width;
    group.broadcast(c.data);
    group.broadcast(c.variance);
}

// The scene's reference variant rendered in two independent halves (seeds seed and seed + 1,
// spp / 2 each): their mean is the reference and (a - b)^2 / 4 per voxel the variance of that
// mean (valid for any sampler), which the measures take out. Both are kept in OUT/cache under
// `key` (reference_keys()). Empty when the user stopped it. (A reference file is read by
// check_experiment().)
std::optional<Cube> reference_cube(const Experiment& e, const SceneSpec& scene,
                                   const std::string& key, const RunnerOptions& options,
                                   int threads, const fs::path& dir) {
    const std::string stem = (dir / "cache" / ("reference-" + scene.name + "-" + key)).string();
    const std::string mean_file = stem + "-mean.npy", variance_file = stem + "-variance.npy";
    // A distributed study: rank 0 keeps the cache, every process renders, all get the cube.
    StudyGroup* group = options.group;
    const bool root = !group || group->rank() == 0;
    std::string cached = root && fs::exists(mean_file) && fs::exists(variance_file) ? "yes" : "";
    if (group) group->broadcast(cached);
    std::optional<Cube> r;
    if (!cached.empty()) {
        if (root) {
            r = read_reference_file(mean_file);
            r->variance = read_reference_file(variance_file).data;
        }
    } else {
        if (options.progress && root)
            fmt::print(stderr,
                       "rendering the reference of {}: {} at {} spp in two halves (cached in "
                       "{}-*.npy){}\n",
                       scene.name, e.reference.variant, e.reference.spp, stem,
                       group ? fmt::format(" with {} processes", group->everyone().size()) : "");
        r = render_reference(e, scene, options, threads, dir);
        if (!r) return std::nullopt;
        if (root) write_reference_cache(*r, mean_file, variance_file);
    }
    if (group) {
        if (!r) r.emplace();  // filled by rank 0's
        share_cube(*group, *r);
    }
    return r;
}

// The reference variant rendered in two halves (a distributed render each in a distributed
// study, whose result only rank 0 holds); empty when the user stopped it.
std::optional<Cube> render_reference(const Experiment& e, const SceneSpec& scene,
                                     const RunnerOptions& options, int threads,
                                     const fs::path& dir) {
    const LoadOptions lo = load_options(scene, *e.find_variant(e.reference.variant), options);
    const uint32_t half = std::max<uint32_t>(1, e.reference.spp / 2);
    if (options.group && threads == 0) threads = options.group->default_threads();
    Rendered a = render_run(scene.file, lo, e.reference.seed, half, threads, options,
                            scratch_folder(dir, options), true, {}, options.group);
    if (a.stopped) return std::nullopt;
    Rendered b = render_run(scene.file, lo, e.reference.seed + 1, half, threads, options,
                            scratch_folder(dir, options), true, {}, options.group);
    if (b.stopped) return std::nullopt;
    Cube r = std::move(a.cube);
    r.variance.resize(r.data.size());
    for (size_t i = 0; i < r.data.size(); ++i) {
        const double x = r.data[i], y = b.cube.data[i];
        r.data[i] = float(0.5 * (x + y));
        r.variance[i] = float(0.25 * (x - y) * (x - y));
    }
    return r;
}

// A finished run's row: what it measured, and its errors against `reference` (none without
// one).
RunRow measured_row(const Experiment& e, const SceneSpec& scene, const Variant& v,
                    const std::string& budget, uint64_t seed, const Rendered& r,
                    const Cube* reference) {
    RunRow row;
    row.scene = scene.name, row.variant = v.name, row.budget = budget, row.seed = seed;
    row.spp = r.stats.spp_done, row.samples = r.stats.camera_samples;
    row.seconds = r.stats.seconds, row.rays = r.stats.rays, row.peak_mb = r.peak_mb;
    row.cores_used = r.stats.seconds > 0 ? r.cpu_seconds / r.stats.seconds : NAN;
    row.rel_mse = row.pixel_rel_mse = row.frame_rel_mse = row.energy = row.rel_mse_raw = NAN;
    if (!reference) return row;
    try {
        check_same_shape(r.cube, *reference);
    } catch (const std::runtime_error& err) {
        throw SceneError(v.location, fmt::format("variant \"{}\" on scene \"{}\": {}; a variant "
                                                 "must keep the film's size and bins",
                                                 v.name, scene.name, err.what()));
    }
    const Cube& ref = *reference;
    row.rel_mse = rel_mse(r.cube, ref);
    row.rel_mse_raw = rel_mse(r.cube, without_variance(ref));
    row.pixel_rel_mse = pixel_rel_mse(r.cube, ref, -INFINITY, INFINITY);
    row.frame_rel_mse = resolved_frame_rel_mse(r.cube, ref);
    row.energy = energy_error(r.cube, ref);
    for (const Window& w : e.windows) row.windows.push_back(rel_mse(r.cube, ref, w.start, w.end));
    for (const PixelSpec& p : e.pixels)
        row.pixels.push_back(pixel_profile_rel_mse(r.cube, ref, p.x, p.y));
    return row;
}

// Renders one run of a study (in this process or a child) at its budget; stopped when the
// user stopped it.
Rendered render_budget(const Experiment& e, const SceneSpec& scene, const Variant& v, size_t budget,
                       uint64_t seed, int threads, const RunnerOptions& options,
                       const fs::path& dir) {
    const LoadOptions lo = load_options(scene, v, options);
    const uint32_t spp = e.timed() ? spp_for_seconds(scene.file, lo, seed, e.time_budgets[budget],
                                                     threads, options, scratch_folder(dir, options))
                                   : e.spp_budgets[budget];
    if (spp == 0) {
        Rendered stopped;
        stopped.stopped = true;
        return stopped;
    }
    if (e.child_processes)
        return render_in_child(scene.file, lo, seed, spp, threads, options,
                               scratch_folder(dir, options));
    return render_run(scene.file, lo, seed, spp, threads, options, scratch_folder(dir, options),
                      e.has_reference());
}

// Embree's raw rate in one scene's geometry: the scene (loaded with the first variant's values)
// and its rays, built once per scene; each measurement appends a row per kind of ray to
// raw_rays.csv.
class RawRayMeter {
public:
    RawRayMeter(const Experiment& e, const SceneSpec& scene, const RunnerOptions& options,
                int threads)
        : seconds_(e.raw_rays_seconds),
          threads_(threads),
          scene_name_(scene.name),
          scene_(load_scene(scene.file, load_options(scene, e.variants.front(), options))) {
        try {
            rays_ = std::make_unique<RawRays>(*scene_, size_t(1) << 20, 1);
        } catch (const std::runtime_error& err) {
            throw SceneError(scene.location,
                             fmt::format("<raw_rays> in scene \"{}\": {}", scene.name, err.what()));
        }
    }
    void measure(const std::string& budget, uint64_t seed, const fs::path& csv) const {
        const bool fresh = !fs::exists(csv);
        std::ostringstream rows;
        if (fresh) rows << "scene,budget,seed,kind,rays,seconds,cores_used\n";
        for (RawRays::Kind kind :
             {RawRays::Kind::incoherent, RawRays::Kind::sorted, RawRays::Kind::shadow}) {
            if (kind == RawRays::Kind::shadow && !rays_->has_shadow_rays()) continue;
            const RawRays::Rate r = rays_->trace(kind, threads_, seconds_);
            rows << scene_name_ << "," << budget << "," << seed << "," << kind_name(kind) << ","
                 << r.rays << "," << number_text(r.seconds) << ","
                 << number_text(r.cpu_seconds / r.seconds) << "\n";
        }
        std::ofstream(csv, std::ios::app) << rows.str();
    }

private:
    double seconds_;
    int threads_;
    std::string scene_name_;
    std::unique_ptr<Scene> scene_;
    std::unique_ptr<RawRays> rays_;
};

std::string progress_line(size_t index, size_t total, const RunRow& row, int worker) {
    const std::string measured =
        std::isfinite(row.rel_mse)
            ? fmt::format("relMSE {:.4g}", row.rel_mse)
            : fmt::format("{:.4g} samples/s", double(row.samples) / std::max(row.seconds, 1e-9));
    return fmt::format(
        "[{}/{}] {} {} budget {} seed {}: {} in {:.2f} s{}{}\n", index, total, row.scene,
        row.variant, row.budget, row.seed, measured, row.seconds,
        std::isfinite(row.peak_mb) ? fmt::format(", peak {:.0f} MB", row.peak_mb) : "",
        worker > 0 ? fmt::format(" (worker {})", worker) : "");
}

// A finished run's lines for the study's files.
RunLines run_lines(const Experiment& e, const RunRow& row, const Rendered& r,
                   const Cube* reference) {
    RunLines lines;
    lines.row = row_line(row);
    if (reference) {
        lines.frames = frame_lines(row, frame_rel_mse(r.cube, *reference));
        for (const PixelSpec& p : e.pixels) lines.profiles += profile_lines(row, p, r.cube);
    }
    return lines;
}

}  // namespace

std::vector<RunRow> read_results(const std::string& csv_path, const Experiment& e) {
    std::vector<RunRow> rows;
    std::string text;
    {
        std::ifstream file(csv_path, std::ios::binary);
        if (!file) return rows;
        text.assign(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
    }
    // A last line without its newline is a row cut short (femto was killed while appending):
    // it is dropped, and its run renders again.
    if (!text.empty() && text.back() != '\n') {
        text.resize(text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1);
        std::ofstream(csv_path, std::ios::binary | std::ios::trunc) << text;
    }
    if (text.empty()) return rows;
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);
    if (line != csv_header(e))
        throw SceneError(
            fmt::format("\"{}\" is not this experiment's results.csv (its header "
                        "differs)",
                        csv_path));
    int number = 1;
    while (std::getline(in, line)) {
        ++number;
        if (line.empty()) continue;
        const std::vector<std::string> f = detail::split(line, ',');
        const size_t columns = kFixedColumns + e.windows.size() + e.pixels.size();
        if (f.size() != columns)
            throw SceneError(fmt::format("{}:{}: expected {} fields, found {}", csv_path, number,
                                         columns, f.size()));
        RunRow r;
        // A whole number up to `max`: std::stoull alone reads "-1" as 2^64 - 1.
        auto count = [](const std::string& s, uint64_t max) {
            const uint64_t v = std::stoull(s);
            if (s.find('-') != std::string::npos || v > max) throw std::out_of_range(s);
            return v;
        };
        try {
            r.scene = f[0], r.variant = f[1], r.budget = f[2];
            r.seed = count(f[3], UINT64_MAX), r.spp = uint32_t(count(f[4], UINT32_MAX));
            r.samples = count(f[5], UINT64_MAX), r.seconds = std::stod(f[6]);
            r.cores_used = std::stod(f[7]), r.rays = count(f[8], UINT64_MAX);
            r.peak_mb = std::stod(f[9]), r.rel_mse = std::stod(f[10]);
            r.pixel_rel_mse = std::stod(f[11]), r.frame_rel_mse = std::stod(f[12]);
            r.energy = std::stod(f[13]), r.rel_mse_raw = std::stod(f[14]);
            for (size_t k = kFixedColumns; k < f.size(); ++k)
                (k < kFixedColumns + e.windows.size() ? r.windows : r.pixels)
                    .push_back(std::stod(f[k]));
        } catch (const std::exception&) {
            throw SceneError(fmt::format("{}:{}: not a row femto bench wrote", csv_path, number));
        }
        rows.push_back(std::move(r));
    }
    return rows;
}

// The runs a results folder already holds, as keys of run_key(); in a distributed study rank 0
// reads them and tells every process.
std::string run_key(const std::string& scene, const std::string& variant, const std::string& budget,
                    uint64_t seed) {
    return scene + "\n" + variant + "\n" + budget + "\n" + std::to_string(seed);
}

std::set<std::string> runs_done(const Experiment& e, const fs::path& csv, StudyGroup* group) {
    std::string text;
    if (!group || group->rank() == 0)
        for (const RunRow& r : read_results(csv.string(), e))
            text += run_key(r.scene, r.variant, r.budget, r.seed) + '\x1f';
    if (group) group->broadcast(text);
    std::set<std::string> done;
    for (size_t start = 0, end; (end = text.find('\x1f', start)) != std::string::npos;
         start = end + 1)
        done.insert(text.substr(start, end - start));
    return done;
}

// Rank 0 writes what the other workers of a distributed study have finished (with
// `until_done`, everything they will send).
void write_received_runs(const RunnerOptions& options, const Experiment& e, const fs::path& dir,
                         bool until_done) {
    if (!options.group || options.group->rank() != 0) return;
    options.group->receive_runs(until_done, [&](const std::string& text) {
        const RunLines lines = RunLines::split(text);
        append_run(dir, e, lines);
        if (options.progress) fmt::print(stderr, "{}", lines.progress);
    });
}

namespace {

// The <pixel>s and a reference file against the film a scene renders into (film_shape()): what
// a study would otherwise find only after rendering its reference or its first run.
void check_against_film(const Experiment& e, const SceneSpec& scene, const Cube& film,
                        const Cube* reference) {
    const size_t H = film.H, W = film.W, T = film.T;
    for (const PixelSpec& p : e.pixels)
        if (p.x < 0 || p.y < 0 || size_t(p.x) >= W || size_t(p.y) >= H)
            throw SceneError(p.location, fmt::format("pixel ({}, {}) is outside scene \"{}\"'s "
                                                     "{} x {} film",
                                                     p.x, p.y, scene.name, W, H));
    if (reference && (reference->H != H || reference->W != W || reference->T != T))
        throw SceneError(e.reference.location,
                         fmt::format("reference \"{}\" is [{}, {}, {}] (H, W, T), but scene \"{}\" "
                                     "renders [{}, {}, {}]",
                                     e.reference.file, reference->H, reference->W, reference->T,
                                     scene.name, H, W, T));
}

// check_experiment(), which also reads the experiment's reference file (if it has one) into
// `reference`, for run_experiment() to measure against without reading it again.
size_t check_experiment(const Experiment& e, const RunnerOptions& options,
                        std::optional<Cube>& reference) {
    if (!e.reference.file.empty()) {
        try {
            reference = read_reference_file(e.reference.file);
        } catch (const SceneError& err) {
            throw SceneError(e.reference.location, err.what());
        }
    }
    size_t pairs = 0;
    for (const SceneSpec& scene : e.scenes)
        for (const Variant& v : e.variants) {
            Cube film;
            try {
                const std::unique_ptr<Scene> loaded =
                    load_scene(scene.file, load_options(scene, v, options));
                loaded->integrator().preprocess(*loaded);
                film = film_shape(loaded->sensor().film());
            } catch (const SceneError& err) {
                throw SceneError(v.location, fmt::format("variant \"{}\" cannot render scene "
                                                         "\"{}\": {}",
                                                         v.name, scene.name, err.what()));
            }
            check_against_film(e, scene, film, reference ? &*reference : nullptr);
            ++pairs;
        }
    return pairs;
}

}  // namespace

size_t check_experiment(const Experiment& e, const RunnerOptions& options) {
    std::optional<Cube> reference;
    return check_experiment(e, options, reference);
}

bool run_experiment(const Experiment& e, const RunnerOptions& options) {
    std::optional<Cube> file_reference;  // the experiment's reference file, read by the check
    check_experiment(e, options, file_reference);
    StudyGroup* group = options.group;
    const bool root = !group || group->rank() == 0;
    if (group && e.raw_rays_seconds > 0)
        throw SceneError(
            "<raw_rays> measures Embree on one machine: run this experiment "
            "without mpirun");
    const fs::path dir(options.out_dir);
    const int threads = options.threads > 0 ? options.threads : e.threads;
    const std::vector<std::string> keys = reference_keys(e, options);
    if (root) prepare_out_dir(setup_digest(e, options, threads, keys), dir);
    const std::set<std::string> done = runs_done(e, dir / "results.csv", group);
    const std::vector<std::string> labels = e.budget_labels();
    const size_t total = e.scenes.size() * labels.size() * e.seeds.size() * e.variants.size();
    Machine machine = Machine::now(threads);
    if (group) machine.workers = group->gather_from_workers(machine.describe());
    // A distributed study gives each (scene, budget, seed) group, all its variants, to one
    // worker in turn: the variants compared in a group run on the same machine, interleaved.
    size_t index = 0, groups = 0;
    bool stopped = false;
    for (size_t s = 0; s < e.scenes.size(); ++s) {
        const SceneSpec& scene = e.scenes[s];
        const bool stop_now = options.stop && options.stop->load();
        stopped = group ? group->everyone().any(stop_now || stopped) : stop_now || stopped;
        if (stopped) break;
        std::optional<Cube> reference;
        if (e.has_reference()) {
            // A reference file fits one scene (load_experiment): it is used once.
            reference = file_reference ? std::exchange(file_reference, std::nullopt)
                                       : reference_cube(e, e.reference_scene(scene), keys[s],
                                                        options, threads, dir);
            stopped = !reference;
            if (stopped) break;
            if (root) write_reference_profiles(e, scene, *reference, dir);
        }
        std::unique_ptr<RawRayMeter> raw;
        if (e.raw_rays_seconds > 0) raw = std::make_unique<RawRayMeter>(e, scene, options, threads);
        for (size_t b = 0; b < labels.size() && !stopped; ++b)
            for (size_t k = 0; k < e.seeds.size() * e.variants.size() && !stopped; ++k) {
                // interleaved: for each seed, A B A B ...
                const uint64_t seed = e.seeds[k / e.variants.size()];
                const Variant& v = e.variants[k % e.variants.size()];
                // Embree's raw rate first in each (budget, seed) group with a run to do.
                if (raw && k % e.variants.size() == 0 &&
                    std::any_of(e.variants.begin(), e.variants.end(), [&](const Variant& w) {
                        return !done.count(run_key(scene.name, w.name, labels[b], seed));
                    }))
                    raw->measure(labels[b], seed, dir / "raw_rays.csv");
                ++index;
                if (k % e.variants.size() == 0) ++groups;
                if (done.count(run_key(scene.name, v.name, labels[b], seed))) continue;
                if (group && int((groups - 1) % size_t(group->workers())) != group->worker_index())
                    continue;
                stopped = options.stop && options.stop->load();
                if (stopped) break;
                const Rendered r = render_budget(e, scene, v, b, seed, threads, options, dir);
                stopped = r.stopped;
                if (stopped) break;
                const RunRow row = measured_row(e, scene, v, labels[b], seed, r,
                                                reference ? &*reference : nullptr);
                RunLines lines = run_lines(e, row, r, reference ? &*reference : nullptr);
                lines.progress =
                    progress_line(index, total, row, group ? group->worker_index() : 0);
                if (!root) {
                    group->send_run(lines.joined());
                    continue;
                }
                append_run(dir, e, lines);
                if (options.progress) fmt::print(stderr, "{}", lines.progress);
                write_received_runs(options, e, dir, false);
            }
    }
    if (group && !root && group->worker_index() >= 0) group->send_run("");  // no more runs
    write_received_runs(options, e, dir, true);
    if (!root) return !stopped;
    write_report(e, read_results((dir / "results.csv").string(), e), machine.finish(), dir);
    return !stopped;
}

bool run_child(const ChildRun& run, const std::atomic<bool>* stop) {
    LoadOptions lo;
    lo.defines = run.defines;
    lo.plugin_dirs = run.plugin_dirs;
    RunnerOptions options;
    options.stop = stop;
    const fs::path stem(run.out_stem);
    // The film writes its outputs (the .npy the study reads among them) from the child: the
    // peak memory is the render's and its outputs', as `femto render --npy` would need.
    const Rendered r = render_run(run.scene_file, lo, run.seed, run.spp, run.threads, options,
                                  stem.string() + "-scratch", false, stem.string());
    if (r.stopped) return false;
    std::ofstream out(stem.string() + ".stats");
    out << fmt::format("{:.17g} {} {} {} {:.17g} {:.17g} {:.17g} {:.17g}\n", r.stats.seconds,
                       r.stats.rays, r.stats.spp_done, r.stats.camera_samples, r.cpu_seconds,
                       r.cube.start, r.cube.bin_width, peak_resident_mb());
    out.close();
    if (!out) throw SceneError(fmt::format("cannot write \"{}.stats\"", stem.string()));
    return true;
}

}  // namespace femto::bench
