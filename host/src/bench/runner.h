// `femto bench`: runs an experiment's renders, measures them against the reference and writes
// results.csv, frames.csv, report.md and plot.svg into the output folder (docs/bench.md).
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "bench/experiment.h"
#include "femto/accumulator.h"
#include "femto/host.h"

namespace femto::bench {

/// The processes of a study run under MPI (`mpirun -np N femto bench`, docs/bench.md): rank 0
/// writes every file; the runs go to one process per machine (the workers), so that no two
/// timed runs share a machine; references render with every process.
class StudyGroup {
public:
    virtual ~StudyGroup() = default;
    virtual int rank() const = 0;
    virtual int workers() const = 0;
    /// This process's index among the workers (rank 0 is worker 0); -1 when it takes no runs.
    virtual int worker_index() const = 0;
    /// Threads of a process rendering a reference when the study names none.
    virtual int default_threads() const = 0;
    /// Every process: the group that shares a reference's passes.
    virtual PassGroup& everyone() = 0;
    /// Every process: adds everyone's `totals` (a reference's film) into rank 0's.
    virtual void combine(const std::vector<Accumulator>& totals) = 0;
    /// Every process: rank 0's value replaces everyone else's.
    virtual void broadcast(std::string& text) = 0;
    virtual void broadcast(std::vector<float>& values) = 0;
    /// Every process: rank 0 receives each worker's `mine`, in worker order (the texts of
    /// processes that take no runs are dropped); the others receive nothing.
    virtual std::vector<std::string> gather_from_workers(const std::string& mine) = 0;
    /// A worker other than rank 0: hands rank 0 a finished run's lines; an empty text says
    /// that this worker has no more runs.
    virtual void send_run(const std::string& text) = 0;
    /// Rank 0: calls `receive` with every run that workers have sent so far; with `until_done`,
    /// waits until every other worker has sent its last.
    virtual void receive_runs(bool until_done,
                              const std::function<void(const std::string&)>& receive) = 0;
};

struct RunnerOptions {
    std::string out_dir;
    int threads = 0;                          ///< overrides the experiment's <threads> when > 0
    std::vector<std::string> plugin_dirs;     ///< searched before every variant's own
    bool progress = true;                     ///< a line per run on stderr
    const std::atomic<bool>* stop = nullptr;  ///< Ctrl-C: finish nothing more, keep the rows
    /// The `femto` program, which runs each render of an <isolation value="process"/> study
    /// (`femto bench-run`, run_child()).
    std::string executable;
    /// The processes of an MPI job sharing the study; null: this process runs it all.
    StudyGroup* group = nullptr;
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

/// Loads every scene of `e` with every variant and lets its integrator check the scene
/// (preprocess), rendering nothing: a variant that cannot run is found before the study spends
/// time on references and runs. Returns the number of (scene, variant) pairs; throws SceneError
/// naming the first pair that cannot run and why. run_experiment() calls it first.
size_t check_experiment(const Experiment& e, const RunnerOptions& options);

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
