// femto_bench_photons: how fast transient_ppm traces its photons and transient_beams its beams
// (issues 14 §4 and 15 §4), which no experiment file can separate from the rest of a render: a
// pass's photon half alone (Integrator::begin_pass(): photon paths traced and stored, the pass's
// maps or beam hierarchy built), in photon paths, beams and rays per second, side by side in the
// same process with the path tracer's rays per second on the same scene (femto's camera-path
// ray loop, bench/README.md "femto's ray rate against Embree's"). Beams per path are counted by
// tracing the same paths with the toolkit's trace_photon_path() (femto/photon_tracing.h), which
// the plugin runs. Medians of interleaved rounds.
//
//   femto_bench_photons [--rounds 7] [--threads N] [--out bench/results/photons.csv]
#include <fmt/format.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <memory>

#include "common.h"
#include "femto/host.h"
#include "femto/integrator.h"
#include "femto/photon_tracing.h"
#include "femto/scene.h"

namespace {

using Clock = std::chrono::steady_clock;

struct Case {
    std::string name, integrator, scene;  // scene: relative to the source tree
    std::vector<std::pair<std::string, std::string>> defines;
    uint32_t photon_passes, path_spp;
};

std::unique_ptr<femto::Scene> load(const Case& c, const std::string& integrator) {
    femto::LoadOptions options;
    options.defines = c.defines;
    options.defines.push_back({"integrator", integrator});
    return femto::load_scene(std::string(FEMTO_BENCH_SOURCE_DIR) + "/" + c.scene, options);
}

struct Rate {
    double per_second = 0, rays_per_second = 0;
    double beams_per_path = 0;  // transient_beams only
};

// Counts the medium segments of photon paths with a finite positive length: the beams
// transient_beams keeps.
struct BeamCounter : femto::PhotonVisitor {
    uint64_t beams = 0;
    void medium_segment(const femto::PhotonPath&, const femto::FreeFlight& flight) {
        if (flight.length > 0 && std::isfinite(flight.length)) ++beams;
    }
};

// Beams per photon path: `paths` paths of pass 1 traced as the plugin traces them.
double beams_per_path(const femto::Scene& scene, uint64_t paths) {
    const auto* rules = dynamic_cast<const femto::MonteCarloIntegrator*>(&scene.integrator());
    if (!rules) throw std::logic_error("transient_beams is not a MonteCarloIntegrator");
    femto::LightPathStarts starts;
    starts.prepare(scene, "transient_beams");
    std::vector<BeamCounter> chunks;
    femto::trace_photon_paths(scene, femto::PassInfo{1, 1, 1, 2, false}, paths, chunks,
                              [&](femto::Sampler& sampler, BeamCounter& counter) {
                                  femto::trace_photon_path(scene, starts, *rules, sampler,
                                                           1.0 / double(paths), counter);
                              });
    uint64_t beams = 0;
    for (const BeamCounter& c : chunks) beams += c.beams;
    return double(beams) / double(paths);
}

// The photon half: `passes` calls of begin_pass() after a one-sample render that prepared the
// integrator (preprocess, the time window). Photon paths per pass: the plugin's default, one per
// pixel (at least 1024).
Rate photon_rate(const Case& c, int threads) {
    auto scene = load(c, c.integrator);
    femto::RenderOptions ro;
    ro.spp = 1;
    ro.threads = threads;
    femto::render(*scene, ro);
    const femto::Film& film = scene->sensor().film();
    const double paths = std::max(1024.0, double(film.width()) * double(film.height()));
    const uint64_t rays0 = scene->rays_traced();
    const auto t0 = Clock::now();
    for (uint32_t p = 1; p <= c.photon_passes; ++p)
        scene->integrator().begin_pass(*scene, femto::PassInfo{p, 1, p, p + 1, false});
    const double s = std::chrono::duration<double>(Clock::now() - t0).count();
    Rate rate{paths * c.photon_passes / s, double(scene->rays_traced() - rays0) / s};
    if (c.integrator == "transient_beams")
        rate.beams_per_path = beams_per_path(*scene, uint64_t(paths));
    return rate;
}

// The path tracer (transient_path) on the same scene: camera samples and rays per second.
Rate path_rate(const Case& c, int threads) {
    auto scene = load(c, "transient_path");
    femto::RenderOptions ro;
    ro.spp = c.path_spp;
    ro.threads = threads;
    const femto::RenderStats st = femto::render(*scene, ro);
    return {double(st.camera_samples) / st.seconds, double(st.rays) / st.seconds};
}

}  // namespace

int main(int argc, char** argv) {
    using namespace femto_bench;
    try {
        std::setvbuf(stdout, nullptr, _IOLBF, 0);
        int rounds = 7, threads = 0;
        std::string out = std::string(FEMTO_BENCH_SOURCE_DIR) + "/bench/results/photons.csv";
        parse_options(argc, argv, {{"--rounds", &rounds}, {"--threads", &threads}},
                      {{"--out", &out}});
        if (rounds < 1 || threads < 0) throw std::invalid_argument("rounds >= 1, threads >= 0");
        std::unique_ptr<tbb::global_control> limit;
        if (threads > 0)
            limit = std::make_unique<tbb::global_control>(
                tbb::global_control::max_allowed_parallelism, size_t(threads));
        const std::vector<Case> cases = {
            {"cornell-box 256x256",
             "transient_ppm",
             "bench/experiments/scenes/cornell-films.xml",
             {{"res", "256"}, {"film", "hdrfilm"}},
             8,
             4},
            {"caustic 128x128",
             "transient_ppm",
             "bench/experiments/scenes/caustic.xml",
             {{"res", "128"}},
             32,
             16},
            {"laser-caustic 128x128",
             "transient_beams",
             "bench/experiments/scenes/laser-caustic.xml",
             {{"res", "128"}, {"bins", "16"}, {"bin_width", "2"}},
             16,
             4},
            {"fog-object 128x128",
             "transient_beams",
             "bench/experiments/scenes/fog-object.xml",
             {{"res", "128"}, {"bins", "16"}, {"bin_width", "0.5"}},
             16,
             4},
        };
        fmt::print("femto_bench_photons: {} | {} cores | threads {} | {} | load {}\n", cpu_model(),
                   sysconf(_SC_NPROCESSORS_ONLN), threads, now_utc(), read_loadavg());
        std::ofstream csv(out);
        csv << "scene,integrator,round,photon_paths_per_s,beams_per_s,photon_mrays_per_s,"
               "path_samples_per_s,path_mrays_per_s\n";
        for (const Case& c : cases) {
            std::vector<double> photons, beams, photon_rays, ratio;
            for (int r = 0; r < rounds; ++r) {
                const Rate ph = photon_rate(c, threads), pt = path_rate(c, threads);
                const double beam_rate = ph.per_second * ph.beams_per_path;
                csv << fmt::format("{},{},{},{},{},{},{},{}\n", c.name, c.integrator, r,
                                   ph.per_second, beam_rate, ph.rays_per_second / 1e6,
                                   pt.per_second, pt.rays_per_second / 1e6);
                photons.push_back(ph.per_second);
                beams.push_back(beam_rate);
                photon_rays.push_back(ph.rays_per_second);
                ratio.push_back(ph.rays_per_second / pt.rays_per_second);
            }
            fmt::print(
                "{} ({}): {:.3g} photon paths/s, {:.3g} beams/s, {:.3g} Mrays/s in the photon "
                "half, {:.3f}x the path tracer's rays/s (medians of {} rounds; ratio range "
                "{:.3f}-{:.3f})\n",
                c.name, c.integrator, median(photons), median(beams), median(photon_rays) / 1e6,
                median(ratio), rounds, *std::min_element(ratio.begin(), ratio.end()),
                *std::max_element(ratio.begin(), ratio.end()));
        }
        fmt::print("load at end: {}\nresults: {}\n", read_loadavg(), out);
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "femto_bench_photons: %s\n", e.what());
        return 1;
    }
}
