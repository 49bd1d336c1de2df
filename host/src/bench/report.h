// `femto bench`: the machine a study ran on, and its report (report.md, plot.svg).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "bench/experiment.h"
#include "bench/runner.h"

namespace femto::bench {

/// Where and when the runs were measured: CPU, cores, threads used, load before and after.
struct Machine {
    std::string host, cpu, date, femto_version, load_before, load_after;
    unsigned cores = 0;
    int threads = 0;  ///< 0: all cores
    /// A distributed study: each worker's describe(), in worker order (rank 0's first).
    std::vector<std::string> workers;
    static Machine now(int threads);
    /// "host (cpu, N cores, load average L before)": a worker's line in the report.
    std::string describe() const;
    /// A copy with the load average read now.
    Machine finish() const;
};

/// Writes report.md (per scene: each variant's runs, its error-vs-time slope with a 95 %
/// interval, its equal-error time ratio against the first variant with a 95 % interval, the
/// median error per budget) and plot.svg (log-log relMSE against seconds, runs and fits).
void write_report(const Experiment& e, const std::vector<RunRow>& rows, const Machine& machine,
                  const std::filesystem::path& dir);

}  // namespace femto::bench
