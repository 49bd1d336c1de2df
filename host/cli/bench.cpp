#include "bench.h"

#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <filesystem>

#include "bench/experiment.h"
#include "bench/runner.h"
#include "distributed.h"
#include "femto/host.h"
#include "femto/log.h"

namespace fs = std::filesystem;

namespace femto::cli {

namespace {

struct BenchArgs {
    std::vector<std::string> experiments;  // one, or several with --check
    std::string out_dir;
    int threads = 0;
    std::vector<std::string> plugin_dirs;
    bool quiet = false;
    bool check = false;
    int runs_per_machine = 1;
} g_args;

struct BenchRunArgs {
    bench::ChildRun run;
    std::vector<std::string> defines;
} g_child;

}  // namespace

CLI::App* add_bench_command(CLI::App& app) {
    CLI::App* bench = app.add_subcommand(
        "bench",
        "Run a convergence study: variants x budgets x seeds against a reference, "
        "error against time (docs/bench.md)");
    bench
        ->add_option("experiment", g_args.experiments,
                     "Experiment file (XML; several with --check)")
        ->required();
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
    bench->add_flag("--check", g_args.check,
                    "Only load every scene with every variant and let each integrator check it, "
                    "check the <pixel>s and a reference file against each film (as every study "
                    "does first), render nothing, and exit: 0 when all can run, 2 naming the "
                    "first that cannot");
    bench
        ->add_option("--runs-per-machine", g_args.runs_per_machine,
                     "Under mpirun: processes of each machine that take runs at the same time "
                     "(default 1, so that timed runs never share a machine; the others help "
                     "render references)")
        ->check(CLI::Range(1, 4096));
    return bench;
}

int run_bench_command(const std::atomic<bool>& stop, Distributed* group) {
    const bool root = !group || group->rank() == 0;
    if (!root) {  // rank 0 speaks for the study
        g_args.quiet = true;
        femto::silence_log(true);
    }
    bench::RunnerOptions options;
    options.threads = g_args.threads;
    options.plugin_dirs = g_args.plugin_dirs;
    if (g_args.check) {
        for (const std::string& file : g_args.experiments) {
            const size_t pairs = bench::check_experiment(bench::load_experiment(file), options);
            if (root)
                fmt::print(stderr, "{}: all {} (scene, variant) pairs load and can render\n", file,
                           pairs);
        }
        return 0;
    }
    if (g_args.experiments.size() != 1)
        throw SceneError("femto bench runs one experiment at a time (several only with --check)");
    const std::string& file = g_args.experiments.front();
    const bench::Experiment e = bench::load_experiment(file);
    options.out_dir =
        g_args.out_dir.empty()
            ? (fs::path(file).parent_path() / (fs::path(file).stem().string() + "-results"))
                  .string()
            : g_args.out_dir;
    options.progress = !g_args.quiet;
    options.stop = &stop;
    std::error_code ec;
    options.executable = fs::read_symlink("/proc/self/exe", ec).string();
    std::unique_ptr<bench::StudyGroup> study =
        group ? make_study_group(*group, g_args.runs_per_machine) : nullptr;
    options.group = study.get();
    bool complete = false;
    try {
        complete = bench::run_experiment(e, options);
    } catch (const fs::filesystem_error& err) {  // a folder or file of the study: bad input
        throw SceneError(err.what());
    }
    if (!g_args.quiet)
        fmt::print(stderr, "{}: {}/report.md, results.csv{}\n",
                   complete ? "done" : "stopped (the finished runs are kept; run again to resume)",
                   options.out_dir, e.has_reference() ? ", frames.csv, plot.svg" : "");
    return complete ? 0 : 130;
}

CLI::App* add_bench_run_command(CLI::App& app) {
    CLI::App* run = app.add_subcommand("bench-run", "One render of a study, in a child process");
    run->group("");  // hidden: `femto bench` starts it
    bench::ChildRun& r = g_child.run;
    run->add_option("--scene", r.scene_file)->required();
    run->add_option("--out", r.out_stem)->required();
    run->add_option("--seed", r.seed)->required();
    run->add_option("--spp", r.spp)->required()->check(CLI::Range(1u, 1u << 30));
    run->add_option("--threads", r.threads)->check(CLI::Range(0, 4096));
    run->add_option("-D", g_child.defines);
    run->add_option("--plugin-dir", r.plugin_dirs);
    return run;
}

int run_bench_run_command(const std::atomic<bool>& stop) {
    for (const std::string& d : g_child.defines) {
        const size_t eq = d.find('=');
        if (eq == std::string::npos)
            throw SceneError(fmt::format("-D \"{}\": expected name=value", d));
        g_child.run.defines.emplace_back(d.substr(0, eq), d.substr(eq + 1));
    }
    return bench::run_child(g_child.run, &stop) ? 0 : 130;
}

}  // namespace femto::cli
