// femto_bench_photons: how fast transient_ppm traces its photons (issue 14 §4), which no
// experiment file can separate from the rest of a render: a pass's photon half alone
// (Integrator::begin_pass(): photon paths traced and stored, the pass's maps built), in photon
// paths and rays per second, side by side in the same process with the path tracer's rays per
// second on the same scene (femto's camera-path ray loop, bench/README.md "femto's ray rate
// against Embree's"). Medians of interleaved rounds.
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
#include "femto/scene.h"

namespace {

using Clock = std::chrono::steady_clock;

struct Case {
    std::string name, scene;  // scene: relative to the source tree
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
};

// The photon half: `passes` calls of begin_pass() after a one-sample render that prepared the
// integrator (preprocess, the time window). Photon paths per pass: the plugin's default, one per
// pixel (at least 1024).
Rate photon_rate(const Case& c, int threads) {
    auto scene = load(c, "transient_ppm");
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
    return {paths * c.photon_passes / s, double(scene->rays_traced() - rays0) / s};
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
        for (int i = 1; i < argc; ++i) {
            const std::string a = argv[i];
            if (a == "--rounds")
                rounds = std::stoi(option_value(argc, argv, i));
            else if (a == "--threads")
                threads = std::stoi(option_value(argc, argv, i));
            else if (a == "--out")
                out = option_value(argc, argv, i);
            else
                throw std::invalid_argument("unknown option " + a);
        }
        if (rounds < 1 || threads < 0) throw std::invalid_argument("rounds >= 1, threads >= 0");
        std::unique_ptr<tbb::global_control> limit;
        if (threads > 0)
            limit = std::make_unique<tbb::global_control>(
                tbb::global_control::max_allowed_parallelism, size_t(threads));
        const std::vector<Case> cases = {
            {"cornell-box 256x256",
             "bench/experiments/scenes/cornell-films.xml",
             {{"res", "256"}, {"film", "hdrfilm"}},
             8,
             4},
            {"caustic 128x128", "bench/experiments/scenes/caustic.xml", {{"res", "128"}}, 32, 16},
        };
        fmt::print("femto_bench_photons: {} | {} cores | threads {} | {} | load {}\n", cpu_model(),
                   sysconf(_SC_NPROCESSORS_ONLN), threads, now_utc(), read_loadavg());
        std::ofstream csv(out);
        csv << "scene,round,photon_paths_per_s,photon_mrays_per_s,path_samples_per_s,"
               "path_mrays_per_s\n";
        for (const Case& c : cases) {
            std::vector<double> photons, photon_rays, ratio;
            for (int r = 0; r < rounds; ++r) {
                const Rate ph = photon_rate(c, threads), pt = path_rate(c, threads);
                csv << fmt::format("{},{},{},{},{},{}\n", c.name, r, ph.per_second,
                                   ph.rays_per_second / 1e6, pt.per_second,
                                   pt.rays_per_second / 1e6);
                photons.push_back(ph.per_second);
                photon_rays.push_back(ph.rays_per_second);
                ratio.push_back(ph.rays_per_second / pt.rays_per_second);
            }
            fmt::print(
                "{}: {:.3g} photon paths/s, {:.3g} Mrays/s in the photon half, {:.3f}x the "
                "path tracer's rays/s (medians of {} rounds; ratio range {:.3f}-{:.3f})\n",
                c.name, median(photons), median(photon_rays) / 1e6, median(ratio), rounds,
                *std::min_element(ratio.begin(), ratio.end()),
                *std::max_element(ratio.begin(), ratio.end()));
        }
        fmt::print("load at end: {}\nresults: {}\n", read_loadavg(), out);
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "femto_bench_photons: %s\n", e.what());
        return 1;
    }
}
