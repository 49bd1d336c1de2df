#include "bench.h"

#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <filesystem>

#include "bench/experiment.h"
#include "bench/runner.h"
#include "femto/host.h"

namespace fs = std::filesystem;

namespace femto::cli {

namespace {

struct BenchArgs {
    std::string experiment, out_dir;
    int threads = 0;
    std::vector<std::string> plugin_dirs;
    bool quiet = false;
} g_args;

}  // namespace

CLI::App* add_bench_command(CLI::App& app) {
    CLI::App* bench = app.add_subcommand(
        "bench",
        "Run a convergence study: variants x budgets x seeds against a reference, "
        "error against time (docs/bench.md)");
    bench->add_option("experiment", g_args.experiment, "Experiment file (XML)")->required();
    bench->add_option("-o,--output", g_args.out_dir,
                      "Results folder (default: EXPERIMENT's name + \"-results\" beside it); a "
                      "re-run resumes from its results.csv");
    bench
        ->add_option("--threads", g_args.threads,
                     "Worker threads (default: the experiment's, "
                     "else all cores)")
        ->check(CLI::Range(1, 4096));
    bench->add_option("--plugin-dir", g_args.plugin_dirs,
                      "Plugin folder searched first by every variant (repeatable)");
    bench->add_flag("-q,--quiet", g_args.quiet, "No line per run");
    return bench;
}

int run_bench_command(const std::atomic<bool>& stop) {
    const bench::Experiment e = bench::load_experiment(g_args.experiment);
    bench::RunnerOptions options;
    options.out_dir = g_args.out_dir.empty()
                          ? (fs::path(g_args.experiment).parent_path() /
                             (fs::path(g_args.experiment).stem().string() + "-results"))
                                .string()
                          : g_args.out_dir;
    options.threads = g_args.threads;
    options.plugin_dirs = g_args.plugin_dirs;
    options.progress = !g_args.quiet;
    options.stop = &stop;
    bool complete = false;
    try {
        complete = bench::run_experiment(e, options);
    } catch (const fs::filesystem_error& err) {  // a folder or file of the study: bad input
        throw SceneError(err.what());
    }
    if (!g_args.quiet)
        fmt::print(stderr, "{}: {}/report.md, results.csv, frames.csv, plot.svg\n",
                   complete ? "done" : "stopped (the finished runs are kept; run again to resume)",
                   options.out_dir);
    return complete ? 0 : 130;
}

}  // namespace femto::cli
