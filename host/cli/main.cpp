// The `femto` command line: render, plugins, viz, --version.
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <charconv>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <thread>

#include "bench.h"
#include "btf.h"
#include "distributed.h"
#include "femto/host.h"
#include "femto/integrator.h"
#include "femto/log.h"
#include "femto/sensor.h"
#include "output_folder.h"
#include "stop_signals.h"
#include "util/strings.h"
#include "viz.h"

namespace fs = std::filesystem;

namespace {

constexpr int kExitOk = 0;
constexpr int kExitInternal = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitInterrupted = 130;
constexpr int kExitSignalBase = 128;  // the shell convention: 128 + signal number
constexpr const char* kPluginDirHelp =
    "Plugin folder, searched before femto's own plugins (repeatable; the first given wins)";

// Ctrl-C (SIGINT), SIGTERM (batch schedulers send it before a time limit) and SIGUSR1 (what
// mpirun forwards to every process; Slurm's --signal) stop the render within a few samples'
// work (in a distributed render: at the end of the current round of passes); what was rendered
// is written and femto exits 128 + the signal. While the outputs are being written, further
// signals only say so: stopping then would lose the render and leave a half-written set.
std::atomic<bool> g_stop{false};
std::atomic<bool> g_writing{false};
std::atomic<int> g_first_signal{0};
std::atomic<int> g_rank{-1};                       // in a distributed render; -1: alone
std::atomic<const char*> g_stop_message{nullptr};  // said on the first stop signal, if set

void say(const char* msg, size_t size) {
    [[maybe_unused]] auto n = write(STDERR_FILENO, msg, size);
}

extern "C" void on_stop_signal(int sig) {
    int none = 0;
    g_first_signal.compare_exchange_strong(none, sig);
    if (g_writing.load()) {
        g_stop.store(true);
        static const char msg[] =
            "\nfemto: still writing the outputs; femto stops as soon as they are complete "
            "(stopping now would lose the render)\n";
        say(msg, sizeof(msg) - 1);
        return;
    }
    if (g_stop.load()) {  // a second signal while rendering: stop now, nothing written yet
        std::signal(sig, SIG_DFL);
        std::raise(sig);
        return;
    }
    g_stop.store(true);
    if (const char* msg = g_rank.load() <= 0 ? g_stop_message.load() : nullptr)
        say(msg, std::strlen(msg));
}

// What a stop signal means to each command, said when the first one arrives.
constexpr const char* kRenderStopMessage =
    "\nfemto: interrupted, writing what was rendered (Ctrl-C again to abort without writing)\n";
constexpr const char* kDistributedRenderStopMessage =
    "\nfemto: interrupted: every process finishes its pass, then rank 0 writes what was "
    "rendered\n";
constexpr const char* kStudyStopMessage =
    "\nfemto: interrupted: the study stops after the runs in progress and keeps every finished "
    "run (Ctrl-C again to stop at once)\n";

void handle_stop_signals(bool on, const char* message = nullptr) {
    g_stop_message.store(message);
    for (int sig : femto::cli::kStopSignals) std::signal(sig, on ? on_stop_signal : SIG_DFL);
}

// Creates the output folder and checks it is writable, before spending time on a render.
// Output names that are folders are refused here: renaming a finished file onto a folder
// fails late, with the system's least helpful message.
void prepare_output(const std::string& out_base) {
    if (out_base.empty() || out_base.back() == '/')
        throw femto::SceneError(
            fmt::format("output \"{}\" must name a file (without extension)", out_base));
    std::error_code ec;
    if (fs::is_directory(out_base, ec))
        throw femto::SceneError(
            fmt::format("output \"{}\" is a folder: name a file in it "
                        "(without extension), e.g. -o {}/render",
                        out_base, out_base));
    for (const char* suffix : {".exr", ".png", ".npy", "_steady.exr"})
        if (fs::is_directory(out_base + suffix, ec))
            throw femto::SceneError(
                fmt::format("cannot write \"{}{}\": a folder has that name", out_base, suffix));
    femto::cli::prepare_output_folder(fs::path(out_base).parent_path());
}

std::pair<std::string, std::string> parse_define(const std::string& text) {
    const size_t eq = text.find('=');
    if (eq == std::string::npos || eq == 0)
        throw femto::SceneError(fmt::format("-D \"{}\": expected name=value", text));
    return {text.substr(0, eq), text.substr(eq + 1)};
}

std::string kind_heading(femto::PluginKind k) { return femto::kind_tag(k); }

// "; did you mean \"x\"?" for the closest of `candidates`, or "".
std::string did_you_mean_clause(const std::string& word,
                                const std::vector<std::string>& candidates) {
    const std::string closest = femto::detail::closest_match(word, candidates);
    return closest.empty() ? std::string() : fmt::format("; did you mean \"{}\"?", closest);
}

// The commands of `app`; hidden ones (`bench-run`, which `femto bench` starts) only when asked.
std::vector<std::string> command_names(const CLI::App& app, bool hidden = false) {
    std::vector<std::string> names;
    for (const CLI::App* sub : app.get_subcommands(std::function<bool(const CLI::App*)>{}))
        if (hidden || !sub->get_group().empty()) names.push_back(sub->get_name());
    return names;
}

// Checks the command words (`render`, `viz peak-time`) before CLI11 parses them: for a
// mistyped one CLI11 only says "A subcommand is required", femto names the word it did not
// know and the closest command. The levels that have commands take no option values, so the
// first word not starting with '-' is the command.
void check_command_words(const CLI::App& app, int argc, char** argv) {
    const CLI::App* level = &app;
    std::string words;  // the commands read so far: "" at the top, then "viz"
    bool asks_for_help = false;
    for (int i = 1; i < argc; ++i) {
        const std::string word = argv[i];
        if (word.rfind('-', 0) == 0) {
            asks_for_help =
                asks_for_help || word == "-h" || word == "--help" || word == "--version";
            continue;
        }
        const std::vector<std::string> names = command_names(*level);
        const std::string kind = words.empty() ? "" : words + " ";  // "viz command"
        const std::vector<std::string> all = command_names(*level, true);
        if (std::find(all.begin(), all.end(), word) == all.end())
            throw femto::SceneError(fmt::format("unknown {0}command \"{1}\"{2} ({0}commands: {3})",
                                                kind, word, did_you_mean_clause(word, names),
                                                femto::detail::join(names)));
        level = level->get_subcommand(word);
        if (level->get_subcommands(std::function<bool(const CLI::App*)>{}).empty()) return;
        words += words.empty() ? word : " " + word;
    }
    if (!asks_for_help && level->get_require_subcommand_min() > 0) {
        const std::string kind = words.empty() ? "" : words + " ";
        throw femto::SceneError(fmt::format("`femto{}` needs a {}command ({}commands: {})",
                                            words.empty() ? "" : " " + words, kind, kind,
                                            femto::detail::join(command_names(*level))));
    }
}

int report_bad_input(const std::string& message) {
    std::fprintf(stderr, "femto: error: %s\n", message.c_str());
    return kExitBadInput;
}

int cmd_plugins(const std::string& name, bool markdown, const femto::LoadOptions& opts) {
    auto plugins = femto::list_plugins(opts);
    std::map<int, std::vector<const femto::PluginDescriptor*>> by_kind;
    for (const auto& [path, d] : plugins) by_kind[int(d->kind)].push_back(d);
    for (auto& [k, v] : by_kind)
        std::sort(v.begin(), v.end(),
                  [](auto* a, auto* b) { return std::string(a->type_name) < b->type_name; });
    auto print_schema = [&](const femto::PluginDescriptor& d, bool md) {
        if (md) {
            fmt::print("### `{}` ({})\n\n{}\n\n", d.type_name, kind_heading(d.kind), d.description);
            if (d.params.empty()) {
                fmt::print("No parameters.\n\n");
                return;
            }
            fmt::print("| parameter | type | default | description |\n|---|---|---|---|\n");
            for (const auto& p : d.params)
                fmt::print("| `{}` | {} | {} | {}{} |\n", p.name, p.type,
                           *p.default_value ? fmt::format("`{}`", p.default_value) : "", p.doc,
                           p.inherited_from ? fmt::format(" *(from {})*", p.inherited_from) : "");
            fmt::print("\n");
        } else {
            fmt::print("<{} type=\"{}\">: {}\n", kind_heading(d.kind), d.type_name, d.description);
            for (const auto& p : d.params)
                fmt::print("  {:<22} {:<16} default {:<12} {}{}\n", p.name, p.type,
                           *p.default_value ? p.default_value : "-", p.doc,
                           p.inherited_from ? fmt::format(" (from {})", p.inherited_from) : "");
        }
    };
    if (!name.empty()) {
        bool found = false;
        for (const auto& [path, d] : plugins)
            if (name == d->type_name) {
                print_schema(*d, markdown);
                fmt::print("  (from {})\n", path);
                found = true;
            }
        if (!found) {
            std::vector<std::string> names;
            for (const auto& [path, d] : plugins) names.push_back(d->type_name);
            throw femto::SceneError(
                fmt::format("no plugin named \"{}\"{} (`femto plugins` lists them)", name,
                            did_you_mean_clause(name, names)));
        }
        return kExitOk;
    }
    if (markdown) {
        fmt::print(
            "# femto plugin reference\n\nGenerated by `femto plugins --markdown` from the plugins' "
            "own schemas; do not edit by hand (regenerate with `scripts/gen-plugin-docs.sh`).\n\n");
        for (const auto& [k, v] : by_kind) {
            fmt::print("## <{}>\n\n", kind_heading(femto::PluginKind(k)));
            for (auto* d : v) print_schema(*d, true);
        }
        return kExitOk;
    }
    for (const auto& [k, v] : by_kind) {
        fmt::print("{}:\n", kind_heading(femto::PluginKind(k)));
        for (auto* d : v) fmt::print("  {:<18} {}\n", d->type_name, d->description);
    }
    return kExitOk;
}

// A CLI11 check that an option is a whole number in [lo, hi], with a plain message (CLI11's
// own range check prints its bounds as 300-digit doubles and lets "-1" wrap around).
CLI::Validator whole_number_in(uint64_t lo, uint64_t hi) {
    return CLI::Validator(
        [lo, hi](std::string& text) -> std::string {
            uint64_t v = 0;
            const char* end = text.data() + text.size();
            const auto [ptr, ec] = std::from_chars(text.data(), end, v);
            if (text.empty() || ec != std::errc() || ptr != end || v < lo || v > hi)
                return fmt::format("expected a whole number from {} to {}, got \"{}\"", lo, hi,
                                   text);
            return {};
        },
        fmt::format("INT in [{}, {}]", lo, hi));
}

// The output base without an image extension the user may have given (-o out/name.exr).
std::string strip_output_extension(std::string out_base) {
    const std::string ext = fs::path(out_base).extension().string();
    if (ext == ".exr" || ext == ".png" || ext == ".npy") out_base.resize(out_base.size() - 4);
    return out_base;
}

// What the film and the integrator accumulate, for a distributed render to combine.
std::vector<femto::Accumulator> render_totals(femto::Scene& scene) {
    std::vector<femto::Accumulator> totals = scene.sensor().film().accumulators();
    for (const femto::Accumulator& a : scene.integrator().accumulators()) totals.push_back(a);
    return totals;
}

// A distributed render: adds every process's film into rank 0's and the statistics with it.
// Returns false in the processes that have nothing to write (all but rank 0).
bool combine_processes(femto::cli::Distributed& group, femto::Scene& scene,
                       femto::RenderStats& stats, bool quiet) {
    const auto start = std::chrono::steady_clock::now();
    const std::vector<femto::Accumulator> totals = render_totals(scene);
    group.combine(totals);
    stats = group.combine_stats(stats);
    if (group.rank() != 0) return false;
    if (!quiet) {
        uint64_t bytes = 0;
        for (const femto::Accumulator& a : totals) bytes += a.count * a.element_bytes();
        const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
        fmt::print(stderr,
                   "combined the films of {} processes ({:.1f} MiB from each) in {:.2f} s\n",
                   group.size(), double(bytes) / double(1 << 20), took.count());
    }
    return true;
}

// What `femto render` was asked for on its command line.
struct RenderArgs {
    std::string scene_path, out_base;
    std::vector<std::string> defines;
    uint32_t spp = 0;
    int threads = 0;
    uint64_t seed = 0;
    bool quiet = false, npy = false;
};

CLI::App* add_render_command(CLI::App& app, RenderArgs& a, femto::LoadOptions& opts) {
    auto* render = app.add_subcommand("render", "Render a scene");
    render->add_option("scene", a.scene_path, "Scene file (Mitsuba 0.6 / 3.x XML)")->required();
    render->add_option("-o,--output", a.out_base,
                       "Output path, without extension or with .exr/.png/.npy (default: scene "
                       "name)");
    render->add_option("-D", a.defines, "Set a scene parameter: -D name=value (repeatable)");
    render->add_option("--spp", a.spp, "Samples per pixel (overrides the sampler)")
        ->check(whole_number_in(1, std::numeric_limits<uint32_t>::max()));
    render->add_option("--threads", a.threads, "Worker threads (default: all cores)")
        ->check(whole_number_in(1, 4096));
    render->add_option("--seed", a.seed, "Random seed")
        ->check(whole_number_in(0, std::numeric_limits<uint64_t>::max()));
    render->add_option("--plugin-dir", opts.plugin_dirs, kPluginDirHelp);
    render->add_flag("--lenient", opts.lenient,
                     "Warn about unknown/unused parameters instead of failing");
    render->add_flag("-q,--quiet", a.quiet, "No progress or summary output");
    render->add_flag("--npy", a.npy,
                     "Transient films: also write OUTBASE.npy (float32 [H, W, T, C])");
    return render;
}

int cmd_render(RenderArgs args, femto::LoadOptions opts, femto::cli::Distributed* group) {
    const bool root = !group || group->rank() == 0;
    if (!root) {  // rank 0 speaks for the job
        args.quiet = true;
        femto::silence_log(true);
    }
    for (const auto& d : args.defines) {
        auto define = parse_define(d);
        // Which of two values would win is not obvious, and the loser would never be checked.
        for (const auto& [name, value] : opts.defines)
            if (name == define.first)
                throw femto::SceneError(fmt::format("-D {} is given twice (\"{}\" and \"{}\")",
                                                    name, value, define.second));
        opts.defines.push_back(std::move(define));
    }
    femto::plugin_search_path(opts);  // checks the --plugin-dir folders before any work
    if (args.out_base.empty()) args.out_base = fs::path(args.scene_path).stem().string();
    args.out_base = strip_output_extension(args.out_base);
    if (root) prepare_output(args.out_base);
    // From here on Ctrl-C means "stop rendering and write what was rendered".
    handle_stop_signals(true, group ? kDistributedRenderStopMessage : kRenderStopMessage);
    auto scene = femto::load_scene(args.scene_path, opts);
    if (group) render_totals(*scene);  // a film that cannot be combined fails before rendering
    femto::RenderOptions ro;
    ro.spp = args.spp;
    ro.threads = args.threads > 0 || !group ? args.threads : group->default_threads();
    ro.seed = args.seed;
    ro.progress = !args.quiet && (isatty(STDERR_FILENO) || group);
    ro.progress_lines = group != nullptr;  // mpirun's stderr is a pipe: lines, not a bar
    ro.scene_file = args.scene_path;
    ro.stop = &g_stop;
    ro.group = group;
    femto::RenderStats stats = femto::render(*scene, ro);
    if (group && !combine_processes(*group, *scene, stats, args.quiet))
        return g_first_signal.load() ? kExitSignalBase + g_first_signal.load()
               : stats.interrupted   ? kExitInterrupted
                                     : kExitOk;
    g_writing.store(true);
    femto::RenderInfo info = femto::make_render_info(*scene, ro, stats);
    info.write_npy = args.npy;
    info.processes = group ? uint32_t(group->size()) : 1;
    if (!args.quiet)
        fmt::print(stderr, "{} {} of {} spp in {:.3f} s ({:.3f} M rays/s); writing {}.* ...\n",
                   stats.interrupted ? "Interrupted after" : "Rendered", stats.spp_done,
                   stats.spp_requested, stats.seconds,
                   stats.seconds > 0 ? double(stats.rays) / stats.seconds * 1e-6 : 0.0,
                   args.out_base);
    if (!args.quiet && stats.pilot_seconds > 0)
        fmt::print(stderr, "(the temporal filter's pilot pass took {:.2f} s of it)\n",
                   stats.pilot_seconds);
    if (!args.quiet && stats.pilot_image_spp > 0)
        fmt::print(stderr, "(the temporal filter's pilot was the image's first {} spp)\n",
                   stats.pilot_image_spp);
    if (!args.quiet && stats.adaptive) {
        const femto::Film& film = scene->sensor().film();
        fmt::print(stderr, "adaptive sampling: {:.1f} samples per pixel on average\n",
                   double(stats.camera_samples) / (double(film.width()) * film.height()));
    }
    const auto write_start = std::chrono::steady_clock::now();
    auto files = scene->sensor().film().write(args.out_base, info);
    for (auto& f : scene->integrator().write(args.out_base, info)) files.push_back(std::move(f));
    handle_stop_signals(false);
    if (!args.quiet) {
        const std::chrono::duration<double> took = std::chrono::steady_clock::now() - write_start;
        for (const auto& f : files) fmt::print(stderr, "wrote {}\n", f);
        fmt::print(stderr, "({} files in {:.2f} s)\n", files.size(), took.count());
    }
    if (const int sig = g_first_signal.load()) return kExitSignalBase + sig;
    return stats.interrupted ? kExitInterrupted : kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"femto: a renderer for time-resolved (transient) light transport"};
    app.set_version_flag("--version", std::string("femto ") + femto::version() + "\n" +
                                          femto::cli::distributed_support());
    app.require_subcommand(1);
    femto::LoadOptions opts;

    RenderArgs render_args;
    CLI::App* render = add_render_command(app, render_args, opts);

    auto* plugins = app.add_subcommand("plugins", "List plugins, or print one plugin's parameters");
    std::string plugin_name;
    bool markdown = false;
    plugins->add_option("name", plugin_name, "Plugin type name");
    plugins->add_option("--plugin-dir", opts.plugin_dirs, kPluginDirHelp);
    plugins->add_flag("--markdown", markdown, "Print the reference in Markdown (docs/plugins.md)");
    CLI::App* viz = femto::cli::add_viz_command(app);
    CLI::App* bench = femto::cli::add_bench_command(app);
    CLI::App* btf = femto::cli::add_btf_command(app);
    CLI::App* bench_run = femto::cli::add_bench_run_command(app);

    try {
        check_command_words(app, argc, argv);
        app.parse(argc, argv);
    } catch (const CLI::Success& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        // Usage errors read like every other femto error; the help text stays one --help away.
        return report_bad_input(fmt::format("{} (see femto --help)", e.what()));
    } catch (const femto::SceneError& e) {
        return report_bad_input(e.what());
    }
    // Under mpirun or srun, `femto render` is one process of a distributed render, `femto
    // bench` one of a distributed study.
    std::unique_ptr<femto::cli::Distributed> group;
    if (render->parsed() || bench->parsed()) {
        try {
            group = femto::cli::start_distributed(argc, argv);
        } catch (const std::exception& e) {
            std::fprintf(stderr, "femto: error: %s\n", e.what());
            return kExitInternal;
        }
        if (group) g_rank.store(group->rank());
    }
    // A process of a distributed render that fails ends the whole job (the others would wait
    // for it forever). The others wait a moment first, so that a failure every process meets
    // (a scene error) is reported once, by rank 0.
    auto fail = [&](int code, const std::string& message) {
        if (!group) return std::fprintf(stderr, "femto: %s\n", message.c_str()), code;
        if (group->rank() != 0) std::this_thread::sleep_for(std::chrono::seconds(2));
        const std::string who =
            group->rank() ? fmt::format("femto (process {})", group->rank()) : "femto";
        std::fprintf(stderr, "%s: %s\n", who.c_str(), message.c_str());
        std::fflush(stderr);
        group->abort(code);
        return code;  // (abort() does not return)
    };
    try {
        if (render->parsed()) {
            const int code = cmd_render(render_args, opts, group.get());
            femto::cli::finish_distributed(std::move(group));
            return code;
        }
        if (plugins->parsed()) return cmd_plugins(plugin_name, markdown, opts);
        if (viz->parsed()) return femto::cli::run_viz_command();
        if (btf->parsed()) return femto::cli::run_btf_command();
        if (bench->parsed()) {
            handle_stop_signals(true, kStudyStopMessage);  // stop after the current runs
            const int code = femto::cli::run_bench_command(g_stop, group.get());
            femto::cli::finish_distributed(std::move(group));
            if (const int sig = g_first_signal.load()) return kExitSignalBase + sig;
            return code;
        }
        if (bench_run->parsed()) {
            handle_stop_signals(true);  // Ctrl-C and the study's SIGTERM: stop, write nothing
            const int code = femto::cli::run_bench_run_command(g_stop);
            if (const int sig = g_first_signal.load()) return kExitSignalBase + sig;
            return code;
        }
    } catch (const femto::SceneError& e) {
        return fail(kExitBadInput, std::string("error: ") + e.what());
    } catch (const std::exception& e) {
        return fail(kExitInternal, std::string("internal error: ") + e.what());
    }
    return kExitInternal;
}
