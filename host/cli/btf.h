// `femto btf`: synthetic BTFs with closed forms (synth) and a BTF file's header (info).
#pragma once

namespace CLI {
class App;
}

namespace femto::cli {

/// Adds the `btf` subcommand (synth, info) to `app`.
CLI::App* add_btf_command(CLI::App& app);
/// Runs the parsed `btf` subcommand; returns the exit code. Bad input throws SceneError.
int run_btf_command();

}  // namespace femto::cli
