// femto_bench_transient: what recording time costs, measured side by side in one run on the
// Cornell box (scenes/cornell-box/scene.xml, rewritten in memory for each variant).
//
//  throughput  At one resolution, spp and max_depth, for 1 and 2 threads, interleaved runs of
//              - steady:     `path` (rr_depth > max_depth: no roulette) into an `hdrfilm`;
//              - tpath_hdr:  `transient_path` into the same `hdrfilm` (the integrator alone);
//              - transient:  `transient_path` into a `transient` film of 1024 bins whose
//                window covers every path up to max_depth (computed from the room's size).
//              All three trace the same paths. Reports samples/s and rays/s (RenderStats)
//              per run, their medians and transient/steady ratios. The film is allocated at
//              load time; only render() is timed (no output file is written).
//  memory      Peak RSS (VmHWM) of child processes (this binary re-executed with --child):
//              a 256x256x1024 RGB transient render at 1 spp, the same followed by writing its
//              outputs (EXR), and a baseline that loads and renders the same scene with a
//              1-bin film (the fixed overhead). Reports (peak - baseline) / cube size.
//  error       Error against time: a high-spp reference cube (cached as a .npy in the
//              results folder), then renders at spp = 1, 2, 4, ... with different seeds,
//              recording render seconds and the relative MSE of the cube against the reference
//                  relMSE = sum_v (x_v - r_v)^2 / sum_v r_v^2     (v over all voxels and channels)
//              Rows go to transient_error.csv; error_vs_time() takes any scene XML text and a
//              label, so other temporal filters / time-sampling strategies add their rows.
//
// Output (folder --out): transient_throughput.csv (every run), transient_summary.csv
// (medians, ratios), transient_memory.csv, transient_error.csv (every run),
// transient_error_summary.csv (medians per budget), transient_meta.txt (machine).
#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "common.h"
#include "femto/error.h"
#include "femto/host.h"
#include "femto/image_io.h"
#include "femto/integrator.h"
#include "femto/scene.h"
#include "femto/sensor.h"

namespace fs = std::filesystem;

namespace {

using femto_bench::cpu_model;
using femto_bench::film_cube;
using femto_bench::int_list;
using femto_bench::load1;
using femto_bench::median;
using femto_bench::now_utc;
using femto_bench::option_value;
using femto_bench::read_loadavg;
using femto_bench::read_text;
using femto_bench::rel_mse;
using femto_bench::replace_block;
using femto_bench::replace_once;
using femto_bench::split;
using femto_bench::status_kb;

// -- options -----------------------------------------------------------------------------------

struct Options {
    std::string source_dir = FEMTO_BENCH_SOURCE_DIR;
    std::string out_dir = std::string(FEMTO_BENCH_SOURCE_DIR) + "/bench/results";
    std::vector<std::string> modes = {"throughput", "memory", "error"};
    int runs = 5;
    int res = 128;
    int spp = 32;
    int max_depth = 8;
    int bins = 1024;
    std::vector<int> threads = {1, 2};
    // memory
    int mem_res = 256, mem_bins = 1024;
    // error
    int err_res = 64, err_bins = 256, ref_spp = 8192, err_max_spp = 128, err_seeds = 5,
        err_threads = 2;
    std::string err_scene;  // optional: scene XML file for error mode (default: Cornell box)
    std::string err_label;  // label of its rows
    bool append = false;    // append to transient_error.csv instead of rewriting it
    // child
    std::string child;  // internal: --child baseline|render|write
};

[[noreturn]] void usage(int code) {
    std::puts(
        "femto_bench_transient [options]\n"
        "  --mode M[,M...]   throughput, memory, error (default: all three)\n"
        "  --out DIR         results folder (default bench/results)\n"
        "  --runs N          runs per configuration for throughput (default 5)\n"
        "  --res N --spp N   throughput resolution and spp (default 128, 32)\n"
        "  --max-depth N     max_depth of every variant (default 8)\n"
        "  --bins N          transient bins for throughput (default 1024)\n"
        "  --threads A,B     thread counts for throughput (default 1,2)\n"
        "  --mem-res N --mem-bins N   memory render size (default 256, 1024)\n"
        "  --err-res N --err-bins N --ref-spp N --err-max-spp N --err-seeds N --err-threads N\n"
        "                    error-vs-time settings (default 64, 256, 8192, 128, 5, 2)\n"
        "  --err-scene FILE --label L   error rows for another transient scene (same film\n"
        "                    size as the reference: res, bins, window)\n"
        "  --append          append to transient_error.csv");
    std::exit(code);
}

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&] { return option_value(argc, argv, i); };
        auto next_int = [&]() { return std::stoi(next()); };
        if (a == "-h" || a == "--help") usage(0);
        if (a == "--mode")
            o.modes = split(next(), ',');
        else if (a == "--out")
            o.out_dir = next();
        else if (a == "--runs")
            o.runs = next_int();
        else if (a == "--res")
            o.res = next_int();
        else if (a == "--spp")
            o.spp = next_int();
        else if (a == "--max-depth")
            o.max_depth = next_int();
        else if (a == "--bins")
            o.bins = next_int();
        else if (a == "--threads")
            o.threads = int_list(next());
        else if (a == "--mem-res")
            o.mem_res = next_int();
        else if (a == "--mem-bins")
            o.mem_bins = next_int();
        else if (a == "--err-res")
            o.err_res = next_int();
        else if (a == "--err-bins")
            o.err_bins = next_int();
        else if (a == "--ref-spp")
            o.ref_spp = next_int();
        else if (a == "--err-max-spp")
            o.err_max_spp = next_int();
        else if (a == "--err-seeds")
            o.err_seeds = next_int();
        else if (a == "--err-threads")
            o.err_threads = next_int();
        else if (a == "--err-scene")
            o.err_scene = next();
        else if (a == "--label")
            o.err_label = next();
        else if (a == "--append")
            o.append = true;
        else if (a == "--child")
            o.child = next();
        else
            throw std::invalid_argument("unknown option '" + a + "' (see --help)");
    }
    return o;
}

// -- machine -----------------------------------------------------------------------------------

// -- scene text --------------------------------------------------------------------------------

struct CornellBox {
    std::string xml;  // the transient scene as shipped
    std::string dir;  // its folder (base_dir for relative paths)
    // Geometry used for the time window: the room is [-1, 1]^3, the camera at (0, 0, 3.9).
    static constexpr double kCameraZ = 3.9;
    static constexpr double kStart = 3.5;  // the shipped film's start

    /// Longest optical path with at most `max_depth` segments: the camera segment to the
    /// room's farthest corner, then max_depth - 1 room diagonals (NEE adds the last segment).
    static double longest_path(int max_depth) {
        const double camera = std::sqrt(1.0 + 1.0 + (kCameraZ + 1.0) * (kCameraZ + 1.0));
        return camera + (max_depth - 1) * 2.0 * std::sqrt(3.0);
    }

    /// transient_path into a `transient` film of `bins` bins of `bin_width`.
    std::string transient(int bins, double bin_width) const {
        std::string s =
            replace_once(xml, "<float name=\"bin_width\" value=\"0.05\"/>",
                         fmt::format("<float name=\"bin_width\" value=\"{:.9g}\"/>", bin_width));
        return replace_once(s, "<integer name=\"bins\" value=\"$bins\"/>",
                            fmt::format("<integer name=\"bins\" value=\"{}\"/>", bins));
    }
    /// A transient film whose window covers every path up to max_depth.
    std::string transient_covering(int bins, int max_depth) const {
        return transient(bins, covering_bin_width(bins, max_depth));
    }
    static double covering_bin_width(int bins, int max_depth) {
        // 1% margin, rounded up to 1e-6.
        return std::ceil((longest_path(max_depth) * 1.01 - kStart) / bins * 1e6) / 1e6;
    }
    /// `integrator` (with its parameters) into an hdrfilm.
    std::string steady(const std::string& integrator_xml) const {
        std::string s = replace_block(xml, "<integrator type=\"$integrator\">", "</integrator>",
                                      integrator_xml);
        return replace_block(s, "<film type=\"transient\">", "</film>",
                             "<film type=\"hdrfilm\">\n"
                             "            <integer name=\"width\" value=\"$res\"/>\n"
                             "            <integer name=\"height\" value=\"$res\"/>\n"
                             "            <rfilter type=\"gaussian\"/>\n"
                             "        </film>");
    }
    static std::string path_integrator(int max_depth) {
        return fmt::format(
            "<integrator type=\"path\">\n"
            "        <integer name=\"max_depth\" value=\"$max_depth\"/>\n"
            "        <integer name=\"rr_depth\" value=\"{}\"/>\n"
            "    </integrator>",
            max_depth + 1);
    }
    static std::string tpath_integrator() {
        return "<integrator type=\"transient_path\">\n"
               "        <integer name=\"max_depth\" value=\"$max_depth\"/>\n"
               "    </integrator>";
    }
};

CornellBox load_cornell(const Options& o) {
    CornellBox c;
    c.dir = o.source_dir + "/scenes/cornell-box";
    c.xml = read_text(c.dir + "/scene.xml");
    // Drop the `bins` default so our own value is the only one (the text keeps $bins).
    return c;
}

std::unique_ptr<femto::Scene> load(const std::string& xml, const std::string& base_dir, int res,
                                   int spp, int max_depth, int bins = 0) {
    femto::LoadOptions lo;
    lo.defines = {{"res", std::to_string(res)},
                  {"spp", std::to_string(spp)},
                  {"max_depth", std::to_string(max_depth)}};
    if (bins > 0) lo.defines.push_back({"bins", std::to_string(bins)});
    return femto::load_scene_string(xml, lo, base_dir);
}

// -- throughput --------------------------------------------------------------------------------

struct Variant {
    std::string name, description;
    std::unique_ptr<femto::Scene> scene;
};

void throughput(const Options& o, const CornellBox& box, std::ostream& meta) {
    const double bw = CornellBox::covering_bin_width(o.bins, o.max_depth);
    const double window_end = CornellBox::kStart + bw * o.bins;
    fmt::print(
        "== throughput: Cornell box {0}x{0}, {1} spp, max_depth {2}; transient film {3} "
        "bins x {4} = [{5}, {6:.3f}] (longest path {7:.3f})\n",
        o.res, o.spp, o.max_depth, o.bins, bw, CornellBox::kStart, window_end,
        CornellBox::longest_path(o.max_depth));
    meta << fmt::format(
        "throughput: res {} spp {} max_depth {} bins {} bin_width {} window "
        "[{}, {:.4f}] longest path {:.4f} runs {}\n",
        o.res, o.spp, o.max_depth, o.bins, bw, CornellBox::kStart, window_end,
        CornellBox::longest_path(o.max_depth), o.runs);
    std::vector<Variant> variants;
    variants.push_back({"steady", "path (rr_depth=max_depth+1) -> hdrfilm",
                        load(box.steady(CornellBox::path_integrator(o.max_depth)), box.dir, o.res,
                             o.spp, o.max_depth)});
    variants.push_back(
        {"tpath_hdr", "transient_path -> hdrfilm",
         load(box.steady(CornellBox::tpath_integrator()), box.dir, o.res, o.spp, o.max_depth)});
    variants.push_back({"transient",
                        fmt::format("transient_path -> transient film, {} bins", o.bins),
                        load(box.transient(o.bins, bw), box.dir, o.res, o.spp, o.max_depth)});

    std::ofstream csv(o.out_dir + "/transient_throughput.csv");
    csv << "variant,threads,run,res,spp,max_depth,bins,seconds,samples_per_s,rays_per_s,rays,"
           "load_before,load_after\n";
    std::ofstream sum(o.out_dir + "/transient_summary.csv");
    sum << "variant,threads,runs,median_seconds,median_samples_per_s,median_rays_per_s,"
           "samples_ratio_vs_steady,rays_ratio_vs_steady,rays_per_sample,load_before,"
           "load_after\n";

    // Warm-up (page faults of the films, plugin code, caches): one short render each.
    for (auto& v : variants) {
        femto::RenderOptions ro;
        ro.spp = 1;
        ro.seed = 99;
        femto::render(*v.scene, ro);
    }

    for (int threads : o.threads) {
        const std::string load_before = read_loadavg();
        std::map<std::string, std::vector<double>> sps, rps, secs;
        std::map<std::string, double> rays_per_sample;
        for (int run = 0; run < o.runs; ++run) {
            // Rotate the order each run so drift in the machine's load hits every variant.
            for (size_t k = 0; k < variants.size(); ++k) {
                const size_t i = (size_t(run) + k) % variants.size();
                Variant& v = variants[run % 2 ? variants.size() - 1 - i : i];
                const double lb = load1();
                femto::RenderOptions ro;
                ro.spp = uint32_t(o.spp);
                ro.threads = threads;
                ro.seed = uint64_t(run);
                const femto::RenderStats st = femto::render(*v.scene, ro);
                const double samples = double(st.camera_samples) / st.seconds;
                const double rays = double(st.rays) / st.seconds;
                sps[v.name].push_back(samples);
                rps[v.name].push_back(rays);
                secs[v.name].push_back(st.seconds);
                rays_per_sample[v.name] = double(st.rays) / double(st.camera_samples);
                csv << fmt::format("{},{},{},{},{},{},{},{:.4f},{:.1f},{:.1f},{},{:.2f},{:.2f}\n",
                                   v.name, threads, run, o.res, o.spp, o.max_depth,
                                   v.name == "transient" ? o.bins : 0, st.seconds, samples, rays,
                                   st.rays, lb, load1());
                csv.flush();
                fmt::print(
                    "  threads {} run {} {:<10} {:7.3f} s  {:8.3f} M samples/s  {:7.3f} M "
                    "rays/s\n",
                    threads, run, v.name, st.seconds, samples * 1e-6, rays * 1e-6);
                std::fflush(stdout);
            }
        }
        const std::string load_after = read_loadavg();
        const double base_s = median(sps["steady"]), base_r = median(rps["steady"]);
        fmt::print("  -- {} thread(s), medians of {} runs (load {} -> {}):\n", threads, o.runs,
                   load_before, load_after);
        for (const auto& v : variants) {
            const double ms = median(sps[v.name]), mr = median(rps[v.name]);
            fmt::print(
                "     {:<10} {:8.3f} M samples/s {:7.3f} M rays/s  ratio vs steady: "
                "samples {:.3f}, rays {:.3f}   ({})\n",
                v.name, ms * 1e-6, mr * 1e-6, ms / base_s, mr / base_r, v.description);
            sum << fmt::format("{},{},{},{:.4f},{:.1f},{:.1f},{:.4f},{:.4f},{:.3f},{},{}\n", v.name,
                               threads, o.runs, median(secs[v.name]), ms, mr, ms / base_s,
                               mr / base_r, rays_per_sample[v.name], load_before, load_after);
        }
        // Ratio per run (each run holds every variant back to back), then its median: less
        // sensitive to slow drift than the ratio of medians.
        std::vector<double> paired;
        for (int run = 0; run < o.runs; ++run)
            paired.push_back(sps["transient"][size_t(run)] / sps["steady"][size_t(run)]);
        fmt::print("     median of per-run transient/steady samples/s ratios: {:.3f}\n",
                   median(paired));
        meta << fmt::format("threads {}: median per-run transient/steady ratio {:.4f}\n", threads,
                            median(paired));
    }
}

// -- memory ------------------------------------------------------------------------------------

/// In the child: load, render at 1 spp, optionally write, print the peak RSS.
int memory_child(const Options& o, const std::string& what) {
    const CornellBox box = load_cornell(o);
    const int bins = what == "baseline" ? 1 : o.mem_bins;
    auto scene = load(box.transient(bins, 0.05), box.dir, o.mem_res, 1, o.max_depth);
    const long after_load = status_kb("VmRSS");
    femto::RenderOptions ro;
    ro.spp = 1;
    const femto::RenderStats st = femto::render(*scene, ro);
    const long after_render_hwm = status_kb("VmHWM");
    long after_write_hwm = after_render_hwm;
    if (what == "write") {
        const fs::path tmp =
            fs::temp_directory_path() / fmt::format("femto_bench_mem_{}", getpid());
        fs::create_directories(tmp);
        femto::RenderInfo info = femto::make_render_info(*scene, ro, st);
        scene->sensor().film().write((tmp / "cube").string(), info);
        after_write_hwm = status_kb("VmHWM");
        fs::remove_all(tmp);
    }
    fmt::print("after_load_rss_kb={} peak_render_kb={} peak_write_kb={} render_s={:.3f}\n",
               after_load, after_render_hwm, after_write_hwm, st.seconds);
    return 0;
}

std::map<std::string, double> run_child(const std::string& self, const Options& o,
                                        const std::string& what) {
    const std::string cmd = fmt::format("'{}' --child {} --mem-res {} --mem-bins {} --max-depth {}",
                                        self, what, o.mem_res, o.mem_bins, o.max_depth);
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) throw std::runtime_error("cannot run " + cmd);
    std::string out;
    char buf[512];
    while (std::fgets(buf, sizeof buf, p)) out += buf;
    const int status = pclose(p);
    if (status != 0) throw std::runtime_error("child failed: " + cmd + "\n" + out);
    std::map<std::string, double> kv;
    std::regex re(R"((\w+)=([0-9.]+))");
    for (std::sregex_iterator it(out.begin(), out.end(), re), end; it != end; ++it)
        kv[(*it)[1]] = std::stod((*it)[2]);
    return kv;
}

void memory(const Options& o, std::ostream& meta) {
    const std::string self = fs::read_symlink("/proc/self/exe").string();
    const double cube_mib = double(o.mem_res) * o.mem_res * o.mem_bins * 3 * 4 / (1 << 20);
    fmt::print(
        "== memory: {0}x{0}x{1} RGB cube = {2:.1f} MiB (float32); peak RSS (VmHWM) of "
        "child processes, 1 spp\n",
        o.mem_res, o.mem_bins, cube_mib);
    std::ofstream csv(o.out_dir + "/transient_memory.csv");
    csv << "process,run,after_load_mib,peak_render_mib,peak_write_mib,render_seconds\n";
    std::map<std::string, std::vector<double>> render_peak, write_peak, loaded;
    const int runs = 3;  // peak memory barely varies; three runs show that it does not
    for (int run = 0; run < runs; ++run)
        for (const std::string what : {"baseline", "render", "write"}) {
            auto kv = run_child(self, o, what);
            const double l = kv["after_load_rss_kb"] / 1024, r = kv["peak_render_kb"] / 1024,
                         w = kv["peak_write_kb"] / 1024;
            loaded[what].push_back(l);
            render_peak[what].push_back(r);
            write_peak[what].push_back(w);
            csv << fmt::format("{},{},{:.1f},{:.1f},{:.1f},{:.3f}\n", what, run, l, r, w,
                               kv["render_s"]);
            fmt::print(
                "  run {} {:<8} after load {:7.1f} MiB, peak after render {:7.1f} MiB, "
                "peak after write {:7.1f} MiB\n",
                run, what, l, r, w);
        }
    const double base = median(render_peak["baseline"]);
    const double peak_r = median(render_peak["render"]), peak_w = median(write_peak["write"]);
    const double ratio_r = (peak_r - base) / cube_mib, ratio_w = (peak_w - base) / cube_mib;
    fmt::print("  baseline (1-bin film) peak {:.1f} MiB; cube {:.1f} MiB\n", base, cube_mib);
    fmt::print(
        "  render:         peak {:.1f} MiB, (peak - baseline) / cube = {:.3f}  (goal <= "
        "1.25)\n",
        peak_r, ratio_r);
    fmt::print("  render + write: peak {:.1f} MiB, (peak - baseline) / cube = {:.3f}\n", peak_w,
               ratio_w);
    std::ofstream s(o.out_dir + "/transient_memory_summary.csv");
    s << "cube_mib,baseline_peak_mib,render_peak_mib,render_ratio,write_peak_mib,write_ratio\n";
    s << fmt::format("{:.1f},{:.1f},{:.1f},{:.4f},{:.1f},{:.4f}\n", cube_mib, base, peak_r, ratio_r,
                     peak_w, ratio_w);
    meta << fmt::format(
        "memory: {}x{}x{} cube {:.1f} MiB, baseline {:.1f}, render peak {:.1f} "
        "(ratio {:.3f}), write peak {:.1f} (ratio {:.3f})\n",
        o.mem_res, o.mem_res, o.mem_bins, cube_mib, base, peak_r, ratio_r, peak_w, ratio_w);
}

// -- error against time ------------------------------------------------------------------------

std::string tfilter_of(const std::string& xml) {
    std::smatch m;
    if (std::regex_search(xml, m, std::regex(R"(<tfilter\s+type=\"([^\"]+)\")"))) return m[1];
    return "histogram";
}

struct ErrorSettings {
    int res, max_depth, threads, seeds, max_spp;
};

/// Renders `xml` (a transient scene; $res, $spp, $max_depth are defined) at spp = 1, 2, 4, ...
/// max_spp, `seeds` times each (seed-major, so the budgets interleave), and appends one row
/// per render to `csv`: label, integrator, tfilter, spp, seed, threads, seconds, relmse.
/// Returns the medians per spp: (seconds, relmse).
std::map<int, std::pair<double, double>> error_vs_time(const std::string& label,
                                                       const std::string& xml,
                                                       const std::string& base_dir,
                                                       const std::vector<float>& ref,
                                                       const ErrorSettings& es, std::ostream& csv) {
    const std::string tfilter = tfilter_of(xml);
    std::map<int, std::vector<double>> secs, errs;
    std::string integrator;
    for (int seed = 1; seed <= es.seeds; ++seed)
        for (int spp = 1; spp <= es.max_spp; spp *= 2) {
            auto scene = load(xml, base_dir, es.res, spp, es.max_depth);
            integrator = scene->integrator().type_name();
            femto::RenderOptions ro;
            ro.spp = uint32_t(spp);
            ro.threads = es.threads;
            ro.seed = uint64_t(seed) * 7919;
            const femto::RenderStats st = femto::render(*scene, ro);
            std::vector<size_t> shape;
            const std::vector<float> cube = film_cube(*scene, ro, st, shape);
            const double e = rel_mse(cube, ref);
            secs[spp].push_back(st.seconds);
            errs[spp].push_back(e);
            csv << fmt::format("{},{},{},{},{},{},{:.5f},{:.6g}\n", label, integrator, tfilter, spp,
                               ro.seed, es.threads, st.seconds, e);
            csv.flush();
        }
    std::map<int, std::pair<double, double>> out;
    for (const auto& [spp, s] : secs) {
        out[spp] = {median(s), median(errs[spp])};
        fmt::print("  {:<10} {:<15} {:<10} spp {:4}  {:8.4f} s  relMSE {:.4e}\n", label, integrator,
                   tfilter, spp, out[spp].first, out[spp].second);
    }
    return out;
}

void error(const Options& o, const CornellBox& box, std::ostream& meta) {
    fmt::print(
        "== error vs time: {0}x{0}, {1} bins (window [3.5, {2:.2f}]), max_depth {3}, "
        "reference {4} spp\n",
        o.err_res, o.err_bins, 3.5 + 0.05 * o.err_bins, o.max_depth, o.ref_spp);
    const std::string ref_xml = box.transient(o.err_bins, 0.05);
    const std::string ref_path = fmt::format("{}/ref_cornell_r{}_b{}_d{}_s{}.npy", o.out_dir,
                                             o.err_res, o.err_bins, o.max_depth, o.ref_spp);
    std::vector<float> ref;
    std::vector<size_t> shape;
    if (fs::exists(ref_path)) {
        ref = femto::io::read_npy(ref_path, shape);
        fmt::print("  reference: cached {}\n", ref_path);
    } else {
        auto scene = load(ref_xml, box.dir, o.err_res, o.ref_spp, o.max_depth);
        femto::RenderOptions ro;
        ro.spp = uint32_t(o.ref_spp);
        ro.seed = 123456789;  // not one of the budgets' seeds
        const femto::RenderStats st = femto::render(*scene, ro);
        ref = film_cube(*scene, ro, st, shape);
        femto::io::write_npy(ref_path, shape, ref.data());
        fmt::print("  reference: rendered in {:.1f} s ({} spp), cached as {}\n", st.seconds,
                   o.ref_spp, ref_path);
        meta << fmt::format("error reference: {} spp rendered in {:.2f} s\n", o.ref_spp,
                            st.seconds);
    }
    const std::string path = o.out_dir + "/transient_error.csv";
    const bool header = !o.append || !fs::exists(path);
    std::ofstream csv(path, o.append ? std::ios::app : std::ios::trunc);
    if (header) csv << "label,integrator,tfilter,spp,seed,threads,seconds,relmse\n";
    const ErrorSettings es{o.err_res, o.max_depth, o.err_threads, o.err_seeds, o.err_max_spp};
    std::map<int, std::pair<double, double>> med;
    std::string label = "baseline";  // the shipped scene: ldsampler, histogram
    if (o.err_scene.empty()) {
        med = error_vs_time(label, ref_xml, box.dir, ref, es, csv);
    } else {
        label = o.err_label.empty() ? fs::path(o.err_scene).stem().string() : o.err_label;
        med = error_vs_time(label, read_text(o.err_scene),
                            fs::path(o.err_scene).parent_path().string(), ref, es, csv);
    }
    const std::string spath = o.out_dir + "/transient_error_summary.csv";
    const bool sheader = !o.append || !fs::exists(spath);
    std::ofstream sum(spath, o.append ? std::ios::app : std::ios::trunc);
    if (sheader) sum << "label,spp,median_seconds,median_relmse,runs\n";
    for (const auto& [spp, v] : med)
        sum << fmt::format("{},{},{:.5f},{:.6g},{}\n", label, spp, v.first, v.second, o.err_seeds);
    meta << fmt::format("error: res {} bins {} max_depth {} ref_spp {} seeds {} threads {}\n",
                        o.err_res, o.err_bins, o.max_depth, o.ref_spp, o.err_seeds, o.err_threads);
}

}  // namespace

int main(int argc, char** argv) {
    try {
        // Line-buffered even into a pipe (tee), so progress shows and nothing is duplicated.
        std::setvbuf(stdout, nullptr, _IOLBF, 0);
        const Options o = parse(argc, argv);
        if (!o.child.empty()) return memory_child(o, o.child);
        fs::create_directories(o.out_dir);
        const CornellBox box = load_cornell(o);
        std::ofstream meta(o.out_dir + "/transient_meta.txt");
        meta << "date: " << now_utc() << "\n"
             << "cpu: " << cpu_model() << "\n"
             << "nproc: " << sysconf(_SC_NPROCESSORS_ONLN) << "\n"
             << "build: " << FEMTO_BENCH_BUILD << "\n"
             << "femto: " << femto::version() << "\n"
             << "load average at start: " << read_loadavg() << "\n";
        fmt::print("femto_bench_transient: {} | {} cores | {} | load {}\n", cpu_model(),
                   sysconf(_SC_NPROCESSORS_ONLN), now_utc(), read_loadavg());
        for (const auto& m : o.modes) {
            const auto t0 = std::chrono::steady_clock::now();
            if (m == "throughput")
                throughput(o, box, meta);
            else if (m == "memory")
                memory(o, meta);
            else if (m == "error")
                error(o, box, meta);
            else
                throw std::invalid_argument("unknown mode " + m);
            const double s =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            fmt::print("  ({} took {:.1f} s; load now {})\n", m, s, read_loadavg());
            meta << fmt::format("{} took {:.1f} s, load after: {}\n", m, s, read_loadavg());
            meta.flush();
        }
        meta << "load average at end: " << read_loadavg() << "\n";
        fmt::print("load average at end: {}\n", read_loadavg());
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "femto_bench_transient: %s\n", e.what());
        return 1;
    }
}
