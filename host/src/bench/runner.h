// `femto bench`: runs an experiment's renders, measures them against the reference and writes
// results.csv, frames.csv, report.md and plot.svg into the output folder (docs/bench.md).
#pragma once

#include <atomic>
#include <string>
#include <vector>

#include "bench/experiment.h"

namespace femto::bench {

struct RunnerOptions {
    std::string out_dir;
    int threads = 0;                          ///< overrides the experiment's <threads> when > 0
    std::vector<std::string> plugin_dirs;     ///< searched before every variant's own
    bool progress = true;                     ///< a line per run on stderr
    const std::atomic<bool>* stop = nullptr;  ///< Ctrl-C: finish nothing more, keep the rows
    /// The `femto` program, which runs each render of an <isolation value="process"/> study
    /// (`femto bench-run`, run_child()).
    std::string executable;
};

/// One finished run: a row of results.csv.
struct RunRow {
    std::string scene, variant, budget;
    uint64_t seed = 0;
    uint32_t spp = 0;
    uint64_t samples = 0;  ///< camera samples (spp x pixels)
    double seconds = 0;
    double cores_used = 0;  ///< CPU seconds of the render over its wall-clock seconds
    uint64_t rays = 0;
    double peak_mb = 0;  ///< the child process's peak resident memory; NaN in this process
    double rel_mse = 0, pixel_rel_mse = 0, frame_rel_mse = 0, energy = 0;
    double rel_mse_raw = 0;       ///< rel_mse without the reference's variance taken out
    std::vector<double> windows;  ///< rel_mse per <window>, in the experiment's order
    std::vector<double> pixels;   ///< rel_mse of each <pixel>'s time profile, in order
};

/// Runs what results.csv in `out_dir` does not hold yet (a re-run resumes), then writes the
/// report from every row. Returns false when stopped early (the finished rows are kept).
bool run_experiment(const Experiment& e, const RunnerOptions& options);

/// One render of a study, as `femto bench-run` gives it to a child process.
struct ChildRun {
    std::string scene_file, out_stem;
    std::vector<std::pair<std::string, std::string>> defines;
    std::vector<std::string> plugin_dirs;
    uint64_t seed = 1;
    uint32_t spp = 1;
    int threads = 0;
};

/// Renders `run` in this (child) process and writes OUT_STEM.npy (the cube) and OUT_STEM.stats
/// (what the render measured) for the study's process to read. Returns false when stopped.
bool run_child(const ChildRun& run, const std::atomic<bool>* stop);

/// The rows of a results.csv (for the report and for resuming); throws SceneError when the
/// file is not one `femto bench` wrote for this experiment's windows.
std::vector<RunRow> read_results(const std::string& csv_path, const Experiment& e);

}  // namespace femto::bench
