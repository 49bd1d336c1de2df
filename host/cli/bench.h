// `femto bench EXPERIMENT`: convergence studies (docs/bench.md).
#pragma once

#include <atomic>

namespace CLI {
class App;
}

namespace femto::cli {

/// Adds the `bench` subcommand to `app`.
CLI::App* add_bench_command(CLI::App& app);
/// Runs the parsed `bench` subcommand; `stop` is raised by Ctrl-C. Returns the exit code (130
/// when stopped: the finished runs are kept and reported). Bad input throws SceneError. With a
/// `group` (under mpirun), this process is one of a distributed study (docs/bench.md).
int run_bench_command(const std::atomic<bool>& stop, class Distributed* group);

/// Adds the hidden `bench-run` subcommand: one render of a study in a child process
/// (<isolation value="process"/>), started by `femto bench` itself.
CLI::App* add_bench_run_command(CLI::App& app);
/// Runs the parsed `bench-run` subcommand. Returns 0, or 130 when stopped.
int run_bench_run_command(const std::atomic<bool>& stop);

}  // namespace femto::cli
