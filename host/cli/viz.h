// `femto viz`: pictures from a time-resolved render (thesis ch. 4.3-4.6).
#pragma once

namespace CLI {
class App;
}

namespace femto::cli {

/// Adds the `viz` subcommand (frames, peak-time, rainbow, streak, unwarp) to `app`.
CLI::App* add_viz_command(CLI::App& app);
/// Runs the parsed `viz` subcommand; returns the exit code. Bad input throws SceneError.
int run_viz_command();

}  // namespace femto::cli
