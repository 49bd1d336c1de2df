// femto_bench_kernel: error against wall-clock time of the `kernel` temporal filter
// (progressive kernel density estimation in time, thesis ch. 5.5) next to the `histogram`,
// on the repository's scenes (issue 4, section 3).
//
// For each scene (scenes/<name>/scene.xml at a small resolution, the scene's own sampler,
// window and max_depth):
//  reference  The histogram at many samples per pixel, rendered as two independent halves
//             (two seeds that no budget render uses) with aovs="variance". r = (r1 + r2) / 2.
//             Its own noise, per voxel, two ways: the film's variance AOV, (v1 + v2) / 4 (an
//             i.i.d. formula, exact for the `independent` sampler, an over-estimate for the
//             Owen-scrambled `ldsampler`), and the split-half estimate (r1 - r2)^2 / 4 (valid
//             for any sampler). Cached in the results folder (ref_<scene>_*.npy).
//  budgets    spp = 4, 8, ..., 2048, several seeds; every variant (histogram, kernel, and on
//             the sweep scenes the kernel's alpha / k_neighbors / bandwidth / pilot_spp
//             variants) renders at every (seed, spp), interleaved in one run with the order
//             rotated. Time = wall clock around femto::render() only (the kernel's pilot pass
//             is inside it); the cube is read back untimed through the film's own writer.
//  metrics    against r, with the reference's noise removed (x and r independent:
//             E sum (x - r)^2 = sum E (x - truth)^2 + sum Var r):
//             cube_relmse   (sum (x-r)^2 - sum var_r) / sum r^2 over the whole cube;
//             frame_relmse  the mean over frames with signal (reference frame noise
//                           sum var_r / sum r^2 < 5 %) of the same per frame: every frame
//                           counts equally, the late dim ones as much as the direct peak;
//             frame_relmse_median the median over the same frames;
//             frame_relmse_all the mean over every frame the reference resolves;
//             pixel_relmse  the mean over a few selected pixels of the same over the pixel's
//                           time profile (bins x RGB);
//             cube_relmse_raw (no correction) too.
//  profiles   the selected pixels' time profiles (RGB mean) of the first seed at every budget
//             and of the reference (with its standard deviation): Fig. 5.5 of the thesis.
//
// Output (folder --out): kernel_error.csv (every render), kernel_error_summary.csv (medians
// per scene, variant and spp), kernel_profiles.csv, kernel_scenes.csv (per scene: grid,
// reference, noise figures), kernel_meta.txt. bench/plot_kernel.py adds the speed-ups,
// slopes, tables and plots.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <pugixml.hpp>
#include <sstream>
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

// -- scenes and variants -----------------------------------------------------------------------

struct SceneSpec {
    std::string name;                               // folder under scenes/
    int res;                                        // film width = height
    int ref_spp;                                    // total over the two reference halves
    std::vector<std::pair<double, double>> pixels;  // selected pixels, fractions of the image
    double bandwidth;  // T_1 of the fixed-bandwidth variant (scene units)
};

// Selected pixels: diffuse surfaces whose profiles have both a direct peak and an indirect
// tail (Cornell: back wall, red wall, floor; spheres: floor, back wall, the mirror sphere);
// on the tof-plane (direct light only) the middle and a point near the edge.
std::vector<SceneSpec> default_scenes() {
    return {
        {"cornell-box", 32, 32768, {{0.5, 0.22}, {0.12, 0.5}, {0.62, 0.9}}, 0.2},
        {"tof-plane", 48, 65536, {{0.5, 0.5}, {0.8, 0.3}}, 0.04},
        {"spheres", 48, 32768, {{0.5, 0.9}, {0.5, 0.15}, {0.3, 0.5}}, 0.1},
    };
}

struct Variant {
    std::string label;
    std::string tfilter_xml;  // the <tfilter> element
    std::string tfilter = "histogram";
    double alpha = 0, bandwidth = 0;
    int k = 0, pilot = 0;
};

Variant histogram() { return {"histogram", "<tfilter type=\"histogram\"/>"}; }

Variant kernel(const std::string& label, double alpha, int k, int pilot, double bandwidth) {
    Variant v;
    v.label = label;
    v.tfilter = "kernel";
    v.alpha = alpha;
    v.k = bandwidth > 0 ? 0 : k;
    v.pilot = bandwidth > 0 ? 0 : pilot;
    v.bandwidth = bandwidth;
    std::string x =
        fmt::format("<tfilter type=\"kernel\"><float name=\"alpha\" value=\"{}\"/>", alpha);
    if (bandwidth > 0)
        x += fmt::format("<float name=\"bandwidth\" value=\"{}\"/>", bandwidth);
    else {
        if (k != 40) x += fmt::format("<integer name=\"k_neighbors\" value=\"{}\"/>", k);
        if (pilot != 64) x += fmt::format("<integer name=\"pilot_spp\" value=\"{}\"/>", pilot);
    }
    v.tfilter_xml = x + "</tfilter>";
    return v;
}

/// The variants for one scene: histogram and the default kernel everywhere; on sweep scenes
/// also alpha 0.5 / 0.67 / 0.9, k_neighbors 10, a pilot of 16 spp (with k 40 and k 10) and a
/// fixed bandwidth (alpha 0.8 throughout, except in the alpha variants).
std::vector<Variant> variants_for(const SceneSpec& s, bool sweep) {
    std::vector<Variant> v = {histogram(), kernel("kernel", 0.8, 40, 64, 0)};
    if (sweep) {
        v.push_back(kernel("kernel_a0.5", 0.5, 40, 64, 0));
        v.push_back(kernel("kernel_a0.67", 0.67, 40, 64, 0));
        v.push_back(kernel("kernel_a0.9", 0.9, 40, 64, 0));
        v.push_back(kernel("kernel_k10", 0.8, 10, 64, 0));
        v.push_back(kernel("kernel_p16", 0.8, 40, 16, 0));
        v.push_back(kernel("kernel_k10_p16", 0.8, 10, 16, 0));
        v.push_back(kernel(fmt::format("kernel_bw{}", s.bandwidth), 0.8, 40, 64, s.bandwidth));
    }
    return v;
}

// -- options -----------------------------------------------------------------------------------

struct Options {
    std::string source_dir = FEMTO_BENCH_SOURCE_DIR;
    std::string out_dir = std::string(FEMTO_BENCH_SOURCE_DIR) + "/bench/results";
    std::vector<std::string> scenes = {"cornell-box", "tof-plane", "spheres"};
    std::vector<std::string> sweep = {"cornell-box", "spheres"};
    std::vector<int> budgets = {4, 8, 16, 32, 64, 128, 256, 512, 1024, 2048};
    int seeds = 3;
    int threads = 2;
    std::map<std::string, int> res, ref_spp;  // per-scene overrides
    bool warmup = true;
};

[[noreturn]] void usage(int code) {
    std::puts(
        "femto_bench_kernel [options]\n"
        "  --out DIR            results folder (default bench/results)\n"
        "  --scenes A,B         scenes (default cornell-box,tof-plane,spheres)\n"
        "  --sweep A,B          scenes that also run the alpha / k / pilot / bandwidth variants\n"
        "                       (default cornell-box,spheres; 'none' for none)\n"
        "  --budgets A,B,...    spp budgets (default 4,8,...,2048)\n"
        "  --seeds N            seeds per budget (default 3)\n"
        "  --threads N          render threads (default 2)\n"
        "  --res SCENE=N        resolution of a scene (defaults: cornell-box 32, others 48)\n"
        "  --ref-spp SCENE=N    reference spp of a scene (defaults: cornell-box 32768, tof-plane\n"
        "                       65536, spheres 32768), rendered as two halves\n"
        "  --no-warmup          skip the unrecorded warm-up renders");
    std::exit(code);
}

Options parse(int argc, char** argv) {
    Options o;
    auto scene_int = [](const std::string& v, std::map<std::string, int>& m) {
        const size_t eq = v.find('=');
        if (eq == std::string::npos) throw std::invalid_argument("expected SCENE=N, got " + v);
        m[v.substr(0, eq)] = std::stoi(v.substr(eq + 1));
    };
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
            return argv[++i];
        };
        if (a == "-h" || a == "--help") usage(0);
        if (a == "--out")
            o.out_dir = next();
        else if (a == "--scenes")
            o.scenes = split(next(), ',');
        else if (a == "--sweep") {
            o.sweep = split(next(), ',');
            if (o.sweep == std::vector<std::string>{"none"}) o.sweep.clear();
        } else if (a == "--budgets")
            o.budgets = int_list(next());
        else if (a == "--seeds")
            o.seeds = std::stoi(next());
        else if (a == "--threads")
            o.threads = std::stoi(next());
        else if (a == "--res")
            scene_int(next(), o.res);
        else if (a == "--ref-spp")
            scene_int(next(), o.ref_spp);
        else if (a == "--no-warmup")
            o.warmup = false;
        else
            throw std::invalid_argument("unknown option '" + a + "' (see --help)");
    }
    return o;
}

// -- scene text --------------------------------------------------------------------------------

/// The scene's XML with the film's <tfilter> replaced by `tfilter_xml` and, with `variance`,
/// aovs="variance" added to the film (pugixml, so the rest stays as shipped).
struct SceneText {
    std::string dir, file;
    pugi::xml_document doc;
    std::string sampler;
    double start = 0, bin_width = 0;
    int bins = 0;

    explicit SceneText(const std::string& scene_dir)
        : dir(scene_dir), file(scene_dir + "/scene.xml") {
        const auto r = doc.load_file(file.c_str());
        if (!r) throw std::runtime_error(file + ": " + r.description());
        pugi::xml_node film = doc.child("scene").child("sensor").child("film");
        if (std::string(film.attribute("type").value()) != "transient")
            throw std::runtime_error(file + ": expected a transient film");
        if (!film.child("tfilter")) throw std::runtime_error(file + ": film has no <tfilter>");
        sampler = doc.child("scene").child("sensor").child("sampler").attribute("type").value();
        // The time grid, resolving $name through the scene's <default>s.
        auto value = [&](const char* name) -> std::string {
            pugi::xml_node n = film.find_child_by_attribute("name", name);
            if (!n) throw std::runtime_error(file + ": film lacks " + name);
            std::string v = n.attribute("value").value();
            if (!v.empty() && v[0] == '$') {
                pugi::xml_node d =
                    doc.child("scene").find_child_by_attribute("default", "name", v.c_str() + 1);
                if (!d) throw std::runtime_error(file + ": no default for " + v);
                v = d.attribute("value").value();
            }
            return v;
        };
        start = std::stod(value("start"));
        bin_width = std::stod(value("bin_width"));
        bins = std::stoi(value("bins"));
    }

    std::string with(const std::string& tfilter_xml, bool variance) const {
        pugi::xml_document copy;
        copy.reset(doc);
        pugi::xml_node film = copy.child("scene").child("sensor").child("film");
        pugi::xml_node old = film.child("tfilter");
        pugi::xml_document frag;
        if (!frag.load_string(tfilter_xml.c_str()))
            throw std::runtime_error("bad tfilter XML: " + tfilter_xml);
        film.insert_copy_after(frag.first_child(), old);
        film.remove_child(old);
        if (variance) {
            pugi::xml_node a = film.insert_child_before("string", film.child("rfilter"));
            a.append_attribute("name") = "aovs";
            a.append_attribute("value") = "variance";
        }
        std::ostringstream ss;
        copy.save(ss);
        return ss.str();
    }
};

std::unique_ptr<femto::Scene> load(const std::string& xml, const std::string& base_dir, int res,
                                   int spp) {
    femto::LoadOptions lo;
    lo.defines = {{"res", std::to_string(res)}, {"spp", std::to_string(spp)}};
    return femto::load_scene_string(xml, lo, base_dir);
}

struct Rendered {
    std::vector<float> cube, variance;
    std::vector<size_t> shape;
    double wall = 0, render_seconds = 0, cpu = 0;
};

Rendered render(const std::string& xml, const std::string& base_dir, int res, int spp,
                uint64_t seed, int threads, bool variance) {
    auto scene = load(xml, base_dir, res, spp);
    femto::RenderOptions ro;
    ro.spp = uint32_t(spp);
    ro.threads = threads;
    ro.seed = seed;
    Rendered r;
    const double cpu0 = cpu_seconds();
    const auto t0 = Clock::now();
    const femto::RenderStats st = femto::render(*scene, ro);
    r.wall = std::chrono::duration<double>(Clock::now() - t0).count();
    r.cpu = cpu_seconds() - cpu0;
    r.render_seconds = st.seconds;
    r.cube = film_cube(*scene, ro, st, r.shape, variance ? &r.variance : nullptr);
    return r;
}

// -- reference ---------------------------------------------------------------------------------

struct Reference {
    std::vector<float> mean, var_aov, var_split, var;  // var: the one used for corrections
    std::vector<size_t> shape;                         // H, W, T, 3
    std::string var_kind;
    double seconds = 0;  // render time of both halves (0 when cached)
};

std::string hex_hash(const std::string& s) {
    return fmt::format("{:08x}", uint32_t(std::hash<std::string>{}(s)&0xffffffffu));
}

Reference reference(const SceneSpec& spec, const SceneText& text, const Options& o) {
    const std::string xml = text.with("<tfilter type=\"histogram\"/>", true);
    const std::string base = fmt::format("{}/ref_{}_r{}_s{}_{}", o.out_dir, spec.name, spec.res,
                                         spec.ref_spp, hex_hash(xml));
    Reference ref;
    std::vector<size_t> s1, s2, s3;
    if (fs::exists(base + "_mean.npy") && fs::exists(base + "_varaov.npy") &&
        fs::exists(base + "_varsplit.npy")) {
        ref.mean = femto::io::read_npy(base + "_mean.npy", ref.shape);
        ref.var_aov = femto::io::read_npy(base + "_varaov.npy", s2);
        ref.var_split = femto::io::read_npy(base + "_varsplit.npy", s3);
        fmt::print("  reference: cached {}_*.npy\n", base);
    } else {
        // Two halves with seeds that no budget render uses (budgets: 1000 + 7919 i).
        const int half = spec.ref_spp / 2;
        const Rendered a = render(xml, text.dir, spec.res, half, 900000001ull, o.threads, true);
        const Rendered b = render(xml, text.dir, spec.res, half, 900000002ull, o.threads, true);
        ref.shape = a.shape;
        ref.seconds = a.wall + b.wall;
        const size_t n = a.cube.size();
        ref.mean.resize(n);
        ref.var_aov.resize(n);
        ref.var_split.resize(n);
        for (size_t i = 0; i < n; ++i) {
            ref.mean[i] = 0.5f * (a.cube[i] + b.cube[i]);
            ref.var_aov[i] = 0.25f * (a.variance[i] + b.variance[i]);
            const double d = double(a.cube[i]) - double(b.cube[i]);
            ref.var_split[i] = float(0.25 * d * d);
        }
        femto::io::write_npy(base + "_mean.npy", ref.shape, ref.mean.data());
        femto::io::write_npy(base + "_varaov.npy", ref.shape, ref.var_aov.data());
        femto::io::write_npy(base + "_varsplit.npy", ref.shape, ref.var_split.data());
        fmt::print("  reference: 2 x {} spp in {:.1f} s, cached as {}_*.npy\n", half, ref.seconds,
                   base);
    }
    // The variance AOV assumes independent samples; the ldsampler's scrambled nets have much
    // less variance than that formula says, so there the split-half estimate is used.
    const bool iid = text.sampler == "independent";
    ref.var = iid ? ref.var_aov : ref.var_split;
    ref.var_kind = iid ? "aov" : "split";
    return ref;
}

// -- metrics -----------------------------------------------------------------------------------

struct Metrics {
    double cube_raw = 0, cube = 0, frame = 0, pixel = 0, frame_all = 0, frame_median = 0;
};

struct MetricSetup {
    size_t H = 0, W = 0, T = 0;
    std::vector<int> frames;      // frames with signal (the frame metric)
    std::vector<int> frames_all;  // every frame the reference resolves (frame_relmse_all)
    std::vector<std::pair<int, int>> pixels;  // selected (x, y)
    double sum_r2 = 0, sum_var = 0;
    std::vector<double> frame_r2, frame_var;  // per frame
    std::vector<double> pixel_r2, pixel_var;  // per selected pixel
};

MetricSetup metric_setup(const Reference& ref, const SceneSpec& spec) {
    MetricSetup m;
    m.H = ref.shape[0], m.W = ref.shape[1], m.T = ref.shape[2];
    m.frame_r2.assign(m.T, 0);
    m.frame_var.assign(m.T, 0);
    for (size_t p = 0; p < m.H * m.W; ++p)
        for (size_t t = 0; t < m.T; ++t)
            for (size_t c = 0; c < 3; ++c) {
                const size_t i = (p * m.T + t) * 3 + c;
                m.frame_r2[t] += double(ref.mean[i]) * ref.mean[i];
                m.frame_var[t] += ref.var[i];
            }
    // Frames with signal: the reference resolves them (its noise, sum var / sum r^2, is below
    // 5 %) and they hold at least 1/1000 of the brightest frame's radiance. The second test
    // leaves out the nearly dark frames just before a sharp arrival (in the Cornell box the
    // gap between the lamp seen directly and the first bounce), where any energy a kernel
    // moves there is a relative error of thousands and would decide the mean alone;
    // frame_relmse_all keeps them.
    std::vector<double> frame_sum(m.T, 0);
    for (size_t p = 0; p < m.H * m.W; ++p)
        for (size_t t = 0; t < m.T; ++t)
            for (size_t c = 0; c < 3; ++c) frame_sum[t] += ref.mean[(p * m.T + t) * 3 + c];
    const double brightest = *std::max_element(frame_sum.begin(), frame_sum.end());
    for (size_t t = 0; t < m.T; ++t) {
        m.sum_r2 += m.frame_r2[t];
        m.sum_var += m.frame_var[t];
        if (m.frame_r2[t] > 0 && m.frame_var[t] < 0.05 * m.frame_r2[t]) {
            m.frames_all.push_back(int(t));
            if (frame_sum[t] >= 1e-3 * brightest) m.frames.push_back(int(t));
        }
    }
    for (const auto& [fx, fy] : spec.pixels) {
        const int x = std::min(int(m.W) - 1, int(fx * double(m.W)));
        const int y = std::min(int(m.H) - 1, int(fy * double(m.H)));
        m.pixels.push_back({x, y});
        double r2 = 0, v = 0;
        const size_t base = (size_t(y) * m.W + size_t(x)) * m.T * 3;
        for (size_t i = 0; i < m.T * 3; ++i) {
            r2 += double(ref.mean[base + i]) * ref.mean[base + i];
            v += ref.var[base + i];
        }
        m.pixel_r2.push_back(r2);
        m.pixel_var.push_back(v);
    }
    return m;
}

Metrics metrics(const std::vector<float>& x, const Reference& ref, const MetricSetup& m) {
    if (x.size() != ref.mean.size()) throw std::runtime_error("cube sizes differ");
    std::vector<double> frame_se(m.T, 0);
    double se = 0;
    for (size_t p = 0; p < m.H * m.W; ++p)
        for (size_t t = 0; t < m.T; ++t) {
            const size_t i = (p * m.T + t) * 3;
            double s = 0;
            for (size_t c = 0; c < 3; ++c) {
                const double d = double(x[i + c]) - double(ref.mean[i + c]);
                s += d * d;
            }
            frame_se[t] += s;
            se += s;
        }
    Metrics r;
    r.cube_raw = se / m.sum_r2;
    r.cube = (se - m.sum_var) / m.sum_r2;
    double fsum = 0;
    std::vector<double> per_frame;
    for (int t : m.frames) {
        per_frame.push_back((frame_se[size_t(t)] - m.frame_var[size_t(t)]) / m.frame_r2[size_t(t)]);
        fsum += per_frame.back();
    }
    r.frame = m.frames.empty() ? NAN : fsum / double(m.frames.size());
    r.frame_median = median(per_frame);
    fsum = 0;
    for (int t : m.frames_all)
        fsum += (frame_se[size_t(t)] - m.frame_var[size_t(t)]) / m.frame_r2[size_t(t)];
    r.frame_all = m.frames_all.empty() ? NAN : fsum / double(m.frames_all.size());
    double psum = 0;
    for (size_t k = 0; k < m.pixels.size(); ++k) {
        const auto [px, py] = m.pixels[k];
        const size_t base = (size_t(py) * m.W + size_t(px)) * m.T * 3;
        double s = 0;
        for (size_t i = 0; i < m.T * 3; ++i) {
            const double d = double(x[base + i]) - double(ref.mean[base + i]);
            s += d * d;
        }
        psum += (s - m.pixel_var[k]) / m.pixel_r2[k];
    }
    r.pixel = psum / double(m.pixels.size());
    return r;
}

void write_profiles(std::ostream& csv, const std::string& scene, const std::string& label, int spp,
                    uint64_t seed, const std::vector<float>& x, const std::vector<float>* var,
                    const MetricSetup& m) {
    for (const auto& [px, py] : m.pixels) {
        const size_t base = (size_t(py) * m.W + size_t(px)) * m.T * 3;
        for (size_t t = 0; t < m.T; ++t) {
            const size_t i = base + t * 3;
            const double v = (double(x[i]) + x[i + 1] + x[i + 2]) / 3.0;
            // sd of the RGB mean, channels treated as independent (an upper bound would add
            // the covariances; this is for drawing the reference's band only).
            const double sd =
                var ? std::sqrt((double((*var)[i]) + (*var)[i + 1] + (*var)[i + 2]) / 9.0) : 0.0;
            csv << fmt::format("{},{},{},{},{},{},{},{:.6g},{:.4g}\n", scene, label, spp, seed, px,
                               py, t, v, sd);
        }
    }
}

// -- the run -----------------------------------------------------------------------------------

void run_scene(const SceneSpec& spec, const Options& o, std::ostream& csv, std::ostream& prof,
               std::ostream& scenes_csv, std::ostream& meta,
               std::map<std::tuple<std::string, std::string, int>,
                        std::vector<std::vector<double>>>& summary) {
    const std::string dir = o.source_dir + "/scenes/" + spec.name;
    const SceneText text(dir);
    const bool sweep = std::find(o.sweep.begin(), o.sweep.end(), spec.name) != o.sweep.end();
    const std::vector<Variant> variants = variants_for(spec, sweep);
    fmt::print(
        "== {}: {}x{}, {} bins of {} from {} ({} sampler), reference {} spp; {} variants, "
        "load {}\n",
        spec.name, spec.res, spec.res, text.bins, text.bin_width, text.start, text.sampler,
        spec.ref_spp, variants.size(), read_loadavg());
    const Reference ref = reference(spec, text, o);
    const MetricSetup ms = metric_setup(ref, spec);
    double sum_aov = 0, sum_split = 0;
    for (size_t i = 0; i < ref.var_aov.size(); ++i) {
        sum_aov += ref.var_aov[i];
        sum_split += ref.var_split[i];
    }
    fmt::print(
        "  reference noise (sum var / sum r^2): AOV {:.3e}, split-half {:.3e} (used: {}); "
        "{} of {} frames have signal ({} resolved)\n",
        sum_aov / ms.sum_r2, sum_split / ms.sum_r2, ref.var_kind, ms.frames.size(), ms.T,
        ms.frames_all.size());
    std::string pixels;
    for (const auto& [x, y] : ms.pixels)
        pixels += fmt::format("{}{}:{}", pixels.empty() ? "" : " ", x, y);
    scenes_csv << fmt::format(
        "{},{},{},{},{},{},{},{},{:.2f},{:.6g},{:.6g},{:.6g},{},{},{},{},{},{}\n", spec.name,
        spec.res, text.bins, text.start, text.bin_width, text.sampler, spec.ref_spp, spec.bandwidth,
        ref.seconds, ms.sum_r2, sum_aov / ms.sum_r2, sum_split / ms.sum_r2, ref.var_kind,
        ms.frames.size(), ms.frames.empty() ? -1 : ms.frames.front(),
        ms.frames.empty() ? -1 : ms.frames.back(), ms.frames_all.size(), pixels);
    scenes_csv.flush();
    write_profiles(prof, spec.name, "reference", spec.ref_spp, 0, ref.mean, &ref.var, ms);

    std::vector<std::string> xmls;
    for (const auto& v : variants) xmls.push_back(text.with(v.tfilter_xml, false));
    if (o.warmup)  // unrecorded: plugin loading, TBB workers, page faults
        for (size_t i = 0; i < variants.size(); ++i)
            render(xmls[i], dir, spec.res, o.budgets.front(), 1, o.threads, false);

    const auto t_scene = Clock::now();
    size_t round = 0;
    for (int si = 0; si < o.seeds; ++si) {
        const uint64_t seed = 1000 + 7919ull * uint64_t(si);
        for (int spp : o.budgets) {
            const double l1 = load1();
            for (size_t j = 0; j < variants.size(); ++j) {
                // Rotate the order and reverse it every other round, so drift in the load hits
                // every variant alike.
                size_t idx = (j + round) % variants.size();
                if (round % 2) idx = variants.size() - 1 - idx;
                const Variant& v = variants[idx];
                const Rendered r = render(xmls[idx], dir, spec.res, spp, seed, o.threads, false);
                const Metrics m = metrics(r.cube, ref, ms);
                csv << fmt::format(
                    "{},{},{},{},{},{},{},{},{},{},{:.5f},{:.5f},{:.5f},{:.2f},{:.6g},{:.6g},{:.6g}"
                    ","
                    "{:.6g},{:.6g},{:.6g}\n",
                    spec.name, v.label, v.tfilter, v.alpha, v.k, v.pilot, v.bandwidth, spp, seed,
                    o.threads, r.wall, r.render_seconds, r.cpu, l1, m.cube_raw, m.cube, m.frame,
                    m.pixel, m.frame_all, m.frame_median);
                csv.flush();
                summary[{spec.name, v.label, spp}].push_back({r.wall, m.cube_raw, m.cube, m.frame,
                                                              m.pixel, r.cpu, m.frame_all,
                                                              m.frame_median});
                if (si == 0 && (v.label == "histogram" || v.label == "kernel"))
                    write_profiles(prof, spec.name, v.label, spp, seed, r.cube, nullptr, ms);
            }
            ++round;
            fmt::print("  seed {} spp {:5}: done ({:.0f} s into the scene, load {})\n", seed, spp,
                       std::chrono::duration<double>(Clock::now() - t_scene).count(),
                       read_loadavg());
        }
    }
    prof.flush();
    meta << fmt::format("{}: res {} ref_spp {} ({:.1f} s) variants {} seeds {} took {:.1f} s\n",
                        spec.name, spec.res, spec.ref_spp, ref.seconds, variants.size(), o.seeds,
                        std::chrono::duration<double>(Clock::now() - t_scene).count());
    for (const auto& v : variants) {
        fmt::print("  {:<16}", v.label);
        for (int spp : o.budgets) {
            const auto& rows = summary[{spec.name, v.label, spp}];
            std::vector<double> e;
            for (const auto& r : rows) e.push_back(r[2]);
            fmt::print(" {:.2e}", median(e));
        }
        fmt::print("   (median cube relMSE per budget)\n");
    }
}

}  // namespace

int main(int argc, char** argv) {
    try {
        std::setvbuf(stdout, nullptr, _IOLBF, 0);
        const Options o = parse(argc, argv);
        fs::create_directories(o.out_dir);
        std::vector<SceneSpec> specs;
        for (const auto& name : o.scenes) {
            bool found = false;
            for (SceneSpec s : default_scenes())
                if (s.name == name) {
                    if (o.res.count(name)) s.res = o.res.at(name);
                    if (o.ref_spp.count(name)) s.ref_spp = o.ref_spp.at(name);
                    specs.push_back(s);
                    found = true;
                }
            if (!found) throw std::invalid_argument("unknown scene " + name);
        }
        std::ofstream meta(o.out_dir + "/kernel_meta.txt");
        meta << "date: " << now_utc() << "\n"
             << "cpu: " << cpu_model() << "\n"
             << "nproc: " << sysconf(_SC_NPROCESSORS_ONLN) << "\n"
             << "threads: " << o.threads << "\n"
             << "build: " << FEMTO_BENCH_BUILD << "\n"
             << "femto: " << femto::version() << "\n"
             << "load average at start: " << read_loadavg() << "\n";
        std::string budgets;
        for (int b : o.budgets) budgets += (budgets.empty() ? "" : ",") + std::to_string(b);
        meta << "budgets: " << budgets << "; seeds: " << o.seeds << "\n";
        fmt::print("femto_bench_kernel: {} | {} cores, {} threads | {} | load {}\n", cpu_model(),
                   sysconf(_SC_NPROCESSORS_ONLN), o.threads, now_utc(), read_loadavg());
        std::ofstream csv(o.out_dir + "/kernel_error.csv");
        csv << "scene,label,tfilter,alpha,k_neighbors,pilot_spp,bandwidth,spp,seed,threads,seconds,"
               "render_seconds,cpu_seconds,load1,cube_relmse_raw,cube_relmse,frame_relmse,"
               "pixel_relmse,frame_relmse_all,frame_relmse_median\n";
        std::ofstream prof(o.out_dir + "/kernel_profiles.csv");
        prof << "scene,label,spp,seed,x,y,bin,value,sd\n";
        std::ofstream scenes_csv(o.out_dir + "/kernel_scenes.csv");
        scenes_csv << "scene,res,bins,start,bin_width,sampler,ref_spp,fixed_bandwidth,"
                      "ref_seconds,sum_r2,ref_noise_aov,ref_noise_split,ref_var_used,"
                      "signal_frames,first_signal_frame,last_signal_frame,resolved_frames,pixels\n";
        std::map<std::tuple<std::string, std::string, int>, std::vector<std::vector<double>>>
            summary;
        const auto t0 = Clock::now();
        for (const auto& s : specs) run_scene(s, o, csv, prof, scenes_csv, meta, summary);
        std::ofstream sum(o.out_dir + "/kernel_error_summary.csv");
        sum << "scene,label,spp,runs,median_seconds,median_cube_relmse_raw,median_cube_relmse,"
               "median_frame_relmse,median_pixel_relmse,median_cpu_seconds,median_frame_relmse_all,"
               "median_frame_relmse_median\n";
        for (const auto& [key, rows] : summary) {
            std::vector<std::vector<double>> cols(8);
            for (const auto& r : rows)
                for (size_t c = 0; c < 8; ++c) cols[c].push_back(r[c]);
            sum << fmt::format(
                "{},{},{},{},{:.5f},{:.6g},{:.6g},{:.6g},{:.6g},{:.5f},{:.6g},{:.6g}\n",
                std::get<0>(key), std::get<1>(key), std::get<2>(key), rows.size(), median(cols[0]),
                median(cols[1]), median(cols[2]), median(cols[3]), median(cols[4]), median(cols[5]),
                median(cols[6]), median(cols[7]));
        }
        const double total = std::chrono::duration<double>(Clock::now() - t0).count();
        meta << fmt::format("total {:.1f} s\n", total) << "load average at end: " << read_loadavg()
             << "\n";
        fmt::print("total {:.1f} s; load average at end: {}\n", total, read_loadavg());
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "femto_bench_kernel: %s\n", e.what());
        return 1;
    }
}
