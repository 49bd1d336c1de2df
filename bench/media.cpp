// femto_bench_media: the time-sampling strategies of thesis ch. 5.6 against steady-state
// sampling in participating media, on scenes/fog-object (issue 5, section 5; thesis
// Fig. 5.8-5.10). Histogram reconstruction throughout, as the thesis does, to isolate sampling.
//
// Parts (all at a small resolution, the `independent` sampler, wall clock around
// femto::render() only; the multiple-scattering parts light the scene with a small sphere
// instead of the point light, see scene_text()):
//  media      Fig. 5.8/5.9: sigma_s in {0.2, 0.9, 1.5}, sigma_a = 0.1, phase isotropic and HG
//             g = +-0.8. `steady` (mean_free_path, deterministic, phase) against `time` (the
//             three time strategies combined, each MIS-combined with its steady counterpart:
//             exponential, line_to_point, time, mis) and `time_mfp` (the same with
//             mean-free-path distances) at budgets 16 ... 4096 spp, several seeds.
//  single     Fig. 5.10: single scattering (max_depth 2) at sigma_s 0.9, isotropic: vertices on
//             the camera ray by mean free path (shadow rays from them), equiangular and
//             line_to_point, each alone; the film's `count` AOV gives the samples per frame.
//  combos     every combination of distance x connection x angular x mis (24) at sigma_s 0.9,
//             isotropic: error against wall-clock time, so each strategy's cost counts.
//  bdpt       the media of `media` rendered by transient_bdpt: steady (mean-free-path
//             distances) against exponential distances MIS-combined with mean free paths
//             (bdpt_time), equiangular placed vertices (bdpt_equiangular) and both time
//             strategies together (exponential + line_to_point, bdpt_time_all), time-angular
//             directions MIS-mixed with the phase function (bdpt_angular) and all three time
//             strategies (bdpt_time_full, the thesis' bundle), all weighed by BDPT's MIS; the path
//             tracer's steady sampling alongside (run with --prefix media_bdpt to keep the other
//             parts' CSVs; bench/run_media_bdpt.sh does).
//
// Reference per configuration: exponential + equiangular + time angular with MIS at many spp
// (equiangular has finite variance next to the point light, where line_to_point and shadow
// rays from distance-sampled vertices do not), one render with aovs="variance"; cached in the
// results folder (ref_media_*.npy).
//
// Metrics against the reference r with its own noise removed (E sum (x - r)^2 = sum E (x -
// truth)^2 + sum Var r):
//   frame_relmse  mean over the frames the reference resolves (its noise sum var / sum r^2 <
//                 5 %) of (sum_pixels (x - r)^2 - sum var_r) / sum r^2: every frame counts
//                 equally, the late dim ones as much as the first light (the thesis' relative
//                 error over the frames);
//   pixel_relmse  the same over the time profile of one pixel (a): the pixel with the most
//                 light in the second half of the window;
//   cube_relmse   over the whole cube.
// Output (--out): media_error.csv (every render), media_frames.csv (per frame: error, pixel
// (a)'s value and the reference's, sample counts; first seed), media_meta.txt.
// bench/plot_media.py adds the equal-error sample ratios, tables and plots.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "common.h"
#include "femto/error.h"
#include "femto/host.h"
#include "femto/image_io.h"
#include "femto/scene.h"

namespace fs = std::filesystem;
using namespace femto_bench;

namespace {

using Clock = std::chrono::steady_clock;

struct Strategy {
    std::string name, distance, connection, angular;
    bool mis;
    std::string integrator = "transient_path";
};

const Strategy kSteady{"steady", "mean_free_path", "deterministic", "phase", false};
const Strategy kTime{"time", "exponential", "line_to_point", "time", true};
// The same with mean-free-path distances: the thesis notes mean-free-path sampling is already
// time-uniform when sigma_t is near the exponential's rate, and in denser media the
// exponential (mean_vertices 3 over this window: lambda = 0.375) only adds weight.
const Strategy kTimeMfp{"time_mfp", "mean_free_path", "line_to_point", "time", true};
const Strategy kReference{"reference", "exponential", "equiangular", "time", true};
// BDPT takes every strategy: `mis` mixes exponential distances with mean free paths and
// time-angular directions with the phase function.
const Strategy kBdptSteady{"bdpt_steady", "mean_free_path", "deterministic", "phase",
                           false,         "transient_bdpt"};
const Strategy kBdptTime{"bdpt_time", "exponential", "deterministic",
                         "phase",     true,          "transient_bdpt"};
const Strategy kBdptEquiangular{"bdpt_equiangular", "mean_free_path", "equiangular", "phase", false,
                                "transient_bdpt"};
const Strategy kBdptTimeAll{"bdpt_time_all", "exponential", "line_to_point",
                            "phase",         true,          "transient_bdpt"};
const Strategy kBdptAngular{"bdpt_angular", "mean_free_path", "deterministic", "time",
                            true,           "transient_bdpt"};
// The thesis' full bundle, as the path tracer's `time` above.
const Strategy kBdptTimeFull{"bdpt_time_full", "exponential", "line_to_point",
                             "time",           true,          "transient_bdpt"};

struct Medium {
    double sigma_s, g;
};

struct Options {
    std::string out_dir = FEMTO_BENCH_SOURCE_DIR "/bench/results";
    std::string prefix = "media";  // of the output files
    std::vector<std::string> parts{"media", "single", "combos"};
    std::vector<int> budgets{16, 64, 256, 1024, 4096};
    std::vector<int> combo_budgets{16, 64, 256, 1024};
    int seeds = 7, combo_seeds = 3;
    int res = 8, ref_spp = 65536;
    int threads = 0;
};

[[noreturn]] void usage(int code) {
    fmt::print(
        "usage: femto_bench_media [--out DIR] [--prefix media] [--parts media,single,combos,bdpt]\n"
        "                         [--budgets 16,64,...]\n"
        "                         [--combo-budgets 16,...] [--seeds N] [--combo-seeds N]\n"
        "                         [--res N] [--ref-spp N] [--threads N]\n");
    std::exit(code);
}

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&] { return option_value(argc, argv, i); };
        if (a == "-h" || a == "--help") usage(0);
        if (a == "--out")
            o.out_dir = next();
        else if (a == "--prefix")
            o.prefix = next();
        else if (a == "--parts")
            o.parts = split(next(), ',');
        else if (a == "--budgets")
            o.budgets = int_list(next());
        else if (a == "--combo-budgets")
            o.combo_budgets = int_list(next());
        else if (a == "--seeds")
            o.seeds = std::stoi(next());
        else if (a == "--combo-seeds")
            o.combo_seeds = std::stoi(next());
        else if (a == "--res")
            o.res = std::stoi(next());
        else if (a == "--ref-spp")
            o.ref_spp = std::stoi(next());
        else if (a == "--threads")
            o.threads = std::stoi(next());
        else
            throw std::invalid_argument("unknown option '" + a + "' (see --help)");
    }
    return o;
}

// -- rendering ---------------------------------------------------------------------------------

const std::string kSceneDir = FEMTO_BENCH_SOURCE_DIR "/scenes/fog-object";

// The scene text, with the AOVs the bench reads; for single scattering with max_depth 2. For
// multiple scattering the point light becomes a sphere of radius 0.05 with the same intensity
// (radiance I / (pi 0.05^2)): next to a point light, shadow rays from distance-sampled or
// line-to-point vertices have unbounded variance (the 1 / r^2 falloff; vertices anywhere in
// the fog come arbitrarily close to it), and the errors of such renders scatter over orders of
// magnitude from seed to seed instead of falling as 1 / spp (see bench/README.md). Camera rays
// stay away from the light, so single scattering keeps the point light of Fig. 5.10.
std::string scene_text(bool single) {
    std::string xml = read_text(kSceneDir + "/scene.xml");
    xml = replace_once(xml, "<rfilter type=\"box\"/>",
                       "<string name=\"aovs\" value=\"variance,count\"/><rfilter type=\"box\"/>");
    if (single)
        return replace_once(xml, "<integrator type=\"transient_path\">",
                            "<integrator type=\"transient_path\"><integer name=\"max_depth\" "
                            "value=\"2\"/>");
    return replace_block(
        xml, "<emitter type=\"point\">", "</emitter>",
        "<shape type=\"sphere\"><point name=\"center\" x=\"0.1\" y=\"1.1\" z=\"0.6\"/>"
        "<float name=\"radius\" value=\"0.05\"/><emitter type=\"area\"><rgb "
        "name=\"radiance\" value=\"254.648, 254.648, 254.648\"/></emitter></shape>");
}

struct Rendered {
    std::vector<float> cube, variance, count;
    std::vector<size_t> shape;  // H, W, T, 3
    double wall = 0, render_seconds = 0;
};

Rendered render(const std::string& xml, const Options& o, const Medium& m, const Strategy& s,
                int spp, uint64_t seed) {
    femto::LoadOptions lo;
    lo.defines = {{"res", std::to_string(o.res)},
                  {"spp", std::to_string(spp)},
                  {"bins", "80"},
                  {"bin_width", "0.1"},
                  {"sigma_s", fmt::format("{}", m.sigma_s)},
                  {"sigma_a", "0.1"},
                  {"g", fmt::format("{}", m.g)},
                  {"distance", s.distance},
                  {"connection", s.connection},
                  {"angular", s.angular},
                  {"mis", s.mis ? "true" : "false"}};
    // A splatting integrator (BDPT) has no per-pixel variance AOV; only the reference needs it.
    const bool path = s.integrator == "transient_path";
    const std::string text =
        path ? xml
             : replace_once(replace_once(xml, "<integrator type=\"transient_path\">",
                                         "<integrator type=\"" + s.integrator + "\">"),
                            "value=\"variance,count\"", "value=\"count\"");
    auto scene = femto::load_scene_string(text, lo, kSceneDir);
    femto::RenderOptions ro;
    ro.spp = uint32_t(spp);
    ro.threads = o.threads;
    ro.seed = seed;
    Rendered r;
    const auto t0 = Clock::now();
    const femto::RenderStats st = femto::render(*scene, ro);
    r.wall = std::chrono::duration<double>(Clock::now() - t0).count();
    r.render_seconds = st.seconds;
    // Read back through the film's writer (untimed): the cube, its variance and count AOVs.
    r.cube = film_cube(*scene, ro, st, r.shape, path ? &r.variance : nullptr, &r.count);
    return r;
}

// -- reference and metrics -----------------------------------------------------------------------

struct Reference {
    Rendered r;
    size_t H = 0, W = 0, T = 0;
    std::vector<int> frames;        // resolved frames (whole image)
    std::vector<int> pixel_frames;  // resolved frames of pixel (a)
    size_t pixel = 0;               // y * W + x of pixel (a)
    std::vector<double> frame_r2, frame_var;
    double sum_r2 = 0, sum_var = 0;
    size_t at(size_t p, size_t t, size_t c) const { return (p * T + t) * 3 + c; }
};

Reference reference(const std::string& xml, const Options& o, const Medium& m, bool single) {
    Reference ref;
    const std::string base = fmt::format("{}/ref_media_{}_s{}_g{}_r{}_n{}_{:08x}", o.out_dir,
                                         single ? "single" : "ms", m.sigma_s, m.g, o.res, o.ref_spp,
                                         uint32_t(std::hash<std::string>{}(xml)&0xffffffffu));
    if (fs::exists(base + "_mean.npy") && fs::exists(base + "_var.npy")) {
        std::vector<size_t> s;
        ref.r.cube = femto::io::read_npy(base + "_mean.npy", ref.r.shape);
        ref.r.variance = femto::io::read_npy(base + "_var.npy", s);
        fmt::print("  reference: cached {}_*.npy\n", base);
    } else {
        ref.r = render(xml, o, m, kReference, o.ref_spp, 900000001ull);
        femto::io::write_npy(base + "_mean.npy", ref.r.shape, ref.r.cube.data());
        femto::io::write_npy(base + "_var.npy", ref.r.shape, ref.r.variance.data());
        fmt::print("  reference: {} spp in {:.1f} s, cached as {}_*.npy\n", o.ref_spp, ref.r.wall,
                   base);
    }
    ref.H = ref.r.shape[0];
    ref.W = ref.r.shape[1];
    ref.T = ref.r.shape[2];
    const size_t P = ref.H * ref.W;
    ref.frame_r2.assign(ref.T, 0.0);
    ref.frame_var.assign(ref.T, 0.0);
    std::vector<double> late(P, 0.0);
    for (size_t p = 0; p < P; ++p)
        for (size_t t = 0; t < ref.T; ++t)
            for (size_t c = 0; c < 3; ++c) {
                const double v = ref.r.cube[ref.at(p, t, c)];
                ref.frame_r2[t] += v * v;
                ref.frame_var[t] += ref.r.variance[ref.at(p, t, c)];
                if (t >= ref.T / 2) late[p] += v;
            }
    for (size_t t = 0; t < ref.T; ++t) {
        ref.sum_r2 += ref.frame_r2[t];
        ref.sum_var += ref.frame_var[t];
        if (ref.frame_r2[t] > 0 && ref.frame_var[t] < 0.05 * ref.frame_r2[t])
            ref.frames.push_back(int(t));
    }
    ref.pixel = size_t(std::max_element(late.begin(), late.end()) - late.begin());
    for (size_t t = 0; t < ref.T; ++t) {
        double r2 = 0, var = 0;
        for (size_t c = 0; c < 3; ++c) {
            const double v = ref.r.cube[ref.at(ref.pixel, t, c)];
            r2 += v * v;
            var += ref.r.variance[ref.at(ref.pixel, t, c)];
        }
        if (r2 > 0 && var < 0.05 * r2) ref.pixel_frames.push_back(int(t));
    }
    return ref;
}

struct Metrics {
    double cube = 0, frame = 0, pixel = 0;
    std::vector<double> per_frame;  // every frame; NaN where the reference has no light
};

Metrics metrics(const Rendered& x, const Reference& ref) {
    Metrics m;
    const size_t P = ref.H * ref.W;
    std::vector<double> se(ref.T, 0.0);
    for (size_t p = 0; p < P; ++p)
        for (size_t t = 0; t < ref.T; ++t)
            for (size_t c = 0; c < 3; ++c) {
                const double d = double(x.cube[ref.at(p, t, c)]) - ref.r.cube[ref.at(p, t, c)];
                se[t] += d * d;
            }
    double total = 0;
    m.per_frame.assign(ref.T, NAN);
    for (size_t t = 0; t < ref.T; ++t) {
        total += se[t];
        if (ref.frame_r2[t] > 0) m.per_frame[t] = (se[t] - ref.frame_var[t]) / ref.frame_r2[t];
    }
    m.cube = (total - ref.sum_var) / ref.sum_r2;
    for (int t : ref.frames) m.frame += m.per_frame[size_t(t)];
    m.frame /= double(std::max<size_t>(1, ref.frames.size()));
    for (int t : ref.pixel_frames) {
        double e = 0, r2 = 0, var = 0;
        for (size_t c = 0; c < 3; ++c) {
            const size_t i = ref.at(ref.pixel, size_t(t), c);
            const double d = double(x.cube[i]) - ref.r.cube[i];
            e += d * d;
            r2 += double(ref.r.cube[i]) * ref.r.cube[i];
            var += ref.r.variance[i];
        }
        m.pixel += (e - var) / r2;
    }
    m.pixel /= double(std::max<size_t>(1, ref.pixel_frames.size()));
    return m;
}

// -- parts ---------------------------------------------------------------------------------------

struct Csv {
    std::ofstream error, frames;
};

void write_frames(Csv& csv, const std::string& part, const Medium& m, const Strategy& s, int spp,
                  const Rendered& x, const Reference& ref, const Metrics& mt, double bin_width) {
    const size_t P = ref.H * ref.W;
    for (size_t t = 0; t < ref.T; ++t) {
        double px = 0, pr = 0, count = 0;
        for (size_t c = 0; c < 3; ++c) {
            px += x.cube[ref.at(ref.pixel, t, c)] / 3.0;
            pr += ref.r.cube[ref.at(ref.pixel, t, c)] / 3.0;
        }
        // The count AOV: contributions per pixel and bin, [H][W][T].
        for (size_t p = 0; p < P; ++p) count += x.count[p * ref.T + t];
        csv.frames << fmt::format("{},{},{},{},{},{},{:.4f},{:.6g},{:.6g},{:.6g},{:.6g}\n", part,
                                  m.sigma_s, m.g, s.name, spp, t, (double(t) + 0.5) * bin_width,
                                  mt.per_frame[t], px, pr, count);
    }
}

void run(Csv& csv, const std::string& part, const Medium& m,
         const std::vector<Strategy>& strategies, const std::vector<int>& budgets, int seeds,
         const Options& o, bool single) {
    const std::string xml = scene_text(single);
    fmt::print("{} sigma_s={} g={}\n", part, m.sigma_s, m.g);
    const Reference ref = reference(xml, o, m, single);
    fmt::print("  {} of {} frames resolved, pixel (a) = ({}, {}) with {} resolved frames\n",
               ref.frames.size(), ref.T, ref.pixel % ref.W, ref.pixel / ref.W,
               ref.pixel_frames.size());
    // Interleaved: for every (seed, budget) each strategy once, the order rotated.
    for (int seed = 0; seed < seeds; ++seed)
        for (int spp : budgets)
            for (size_t k = 0; k < strategies.size(); ++k) {
                const Strategy& s = strategies[(k + size_t(seed)) % strategies.size()];
                const Rendered x = render(xml, o, m, s, spp, 1000 + 7919ull * uint64_t(seed));
                const Metrics mt = metrics(x, ref);
                csv.error << fmt::format(
                    "{},{},{},{},{},{},{},{},{},{},{:.6f},{:.6f},{:.6g},{:.6g},{:.6g},{:.3f}\n",
                    part, m.sigma_s, m.g, s.name, s.distance, s.connection, s.angular, s.mis, spp,
                    seed, x.wall, x.render_seconds, mt.cube, mt.frame, mt.pixel, load1());
                if (seed == 0) write_frames(csv, part, m, s, spp, x, ref, mt, 0.1);
                csv.error.flush();
            }
    csv.frames.flush();
}

}  // namespace

int main(int argc, char** argv) try {
    const Options o = parse(argc, argv);
    fs::create_directories(o.out_dir);
    Csv csv;
    const std::string base = o.out_dir + "/" + o.prefix;
    csv.error.open(base + "_error.csv");
    csv.frames.open(base + "_frames.csv");
    csv.error << "part,sigma_s,g,strategy,distance,connection,angular,mis,spp,seed,wall_s,"
                 "render_s,cube_relmse,frame_relmse,pixel_relmse,load1\n";
    csv.frames << "part,sigma_s,g,strategy,spp,frame,t,frame_relmse,pixel,pixel_ref,samples\n";
    {
        std::ofstream meta(base + "_meta.txt");
        meta << "date: " << now_utc() << "\ncpu: " << cpu_model() << " ("
             << sysconf(_SC_NPROCESSORS_ONLN) << " cores)\nbuild: " << FEMTO_BENCH_BUILD
             << "\nload before: " << read_loadavg() << "\nscene: scenes/fog-object, " << o.res
             << "x" << o.res
             << " pixels, 80 bins of 0.1 (window [0, 8)), sigma_a 0.1, histogram\nreference: "
             << o.ref_spp << " spp of " << kReference.distance << " + " << kReference.connection
             << " + " << kReference.angular << " angular, mis\n";
    }
    auto has = [&](const char* p) {
        return std::find(o.parts.begin(), o.parts.end(), p) != o.parts.end();
    };
    if (has("single")) {
        const std::vector<Strategy> single{
            {"mean_free_path", "mean_free_path", "deterministic", "phase", false},
            {"equiangular", "mean_free_path", "equiangular", "phase", false},
            {"line_to_point", "mean_free_path", "line_to_point", "phase", false}};
        run(csv, "single", {0.9, 0.0}, single, o.budgets, o.seeds, o, true);
    }
    if (has("media"))
        for (double g : {0.0, 0.8, -0.8})
            for (double sigma_s : {0.2, 0.9, 1.5})
                run(csv, "media", {sigma_s, g}, {kSteady, kTime, kTimeMfp}, o.budgets, o.seeds, o,
                    false);
    if (has("combos")) {
        std::vector<Strategy> all;
        for (const char* d : {"mean_free_path", "exponential"})
            for (const char* c : {"deterministic", "line_to_point", "equiangular"})
                for (const char* a : {"phase", "time"})
                    for (bool mis : {false, true}) {
                        // mean_free_path/deterministic/phase with MIS is the steady render.
                        if (std::string(d) == "mean_free_path" &&
                            std::string(c) == "deterministic" && std::string(a) == "phase" && mis)
                            continue;
                        all.push_back(
                            {fmt::format("{}/{}/{}{}", d, c, a, mis ? "/mis" : ""), d, c, a, mis});
                    }
        run(csv, "combos", {0.9, 0.0}, all, o.combo_budgets, o.combo_seeds, o, false);
    }
    if (has("bdpt"))
        for (double g : {0.0, 0.8, -0.8})
            for (double sigma_s : {0.2, 0.9, 1.5})
                run(csv, "bdpt", {sigma_s, g},
                    {kSteady, kBdptSteady, kBdptTime, kBdptEquiangular, kBdptTimeAll, kBdptAngular,
                     kBdptTimeFull},
                    o.budgets, o.seeds, o, false);
    std::ofstream(base + "_meta.txt", std::ios::app) << "load after: " << read_loadavg() << "\n";
    return 0;
} catch (const std::exception& e) {
    fmt::print(stderr, "femto_bench_media: {}\n", e.what());
    return 2;
}
