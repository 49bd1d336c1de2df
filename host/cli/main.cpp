// The `femto` command line: render, plugins, viz, --version.
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <charconv>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>

#include "femto/host.h"
#include "femto/integrator.h"
#include "femto/log.h"
#include "femto/sensor.h"
#include "viz.h"

namespace fs = std::filesystem;

namespace {

constexpr int kExitOk = 0;
constexpr int kExitInternal = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitInterrupted = 130;

std::atomic<bool> g_stop{false};

extern "C" void on_sigint(int) {
    if (g_stop.load()) {  // second Ctrl-C: stop now
        std::signal(SIGINT, SIG_DFL);
        std::raise(SIGINT);
        return;
    }
    g_stop.store(true);
    static const char msg[] =
        "\nfemto: interrupted, finishing the current pass (Ctrl-C again to abort)\n";
    [[maybe_unused]] auto n = write(STDERR_FILENO, msg, sizeof(msg) - 1);
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
    fs::path dir = fs::path(out_base).parent_path();
    if (dir.empty()) dir = ".";
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir))
        throw femto::SceneError(fmt::format("cannot create the output folder \"{}\"{}",
                                            dir.string(), ec ? ": " + ec.message() : ""));
    if (access(dir.c_str(), W_OK) != 0)
        throw femto::SceneError(
            fmt::format("the output folder \"{}\" is not writable", dir.string()));
}

std::pair<std::string, std::string> parse_define(const std::string& text) {
    const size_t eq = text.find('=');
    if (eq == std::string::npos || eq == 0)
        throw femto::SceneError(fmt::format("-D \"{}\": expected name=value", text));
    return {text.substr(0, eq), text.substr(eq + 1)};
}

std::string kind_heading(femto::PluginKind k) { return femto::kind_tag(k); }

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
        if (!found)
            throw femto::SceneError(
                fmt::format("no plugin named \"{}\" (run `femto plugins`)", name));
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

int cmd_render(const std::string& scene_path, std::string out_base,
               const std::vector<std::string>& defines, uint32_t spp, int threads, uint64_t seed,
               bool quiet, bool npy, femto::LoadOptions opts) {
    for (const auto& d : defines) opts.defines.push_back(parse_define(d));
    if (out_base.empty()) out_base = fs::path(scene_path).stem().string();
    out_base = strip_output_extension(out_base);
    prepare_output(out_base);
    // From here on Ctrl-C means "stop after the current pass and write what was rendered".
    std::signal(SIGINT, on_sigint);
    auto scene = femto::load_scene(scene_path, opts);
    femto::RenderOptions ro;
    ro.spp = spp;
    ro.threads = threads;
    ro.seed = seed;
    ro.progress = !quiet && isatty(STDERR_FILENO);
    ro.scene_file = scene_path;
    ro.stop = &g_stop;
    const femto::RenderStats stats = femto::render(*scene, ro);
    femto::RenderInfo info = femto::make_render_info(*scene, ro, stats);
    info.write_npy = npy;
    const auto files = scene->sensor().film().write(out_base, info);
    std::signal(SIGINT, SIG_DFL);
    if (!quiet) {
        fmt::print(stderr, "{} {} of {} spp in {:.2f} s ({:.2f} M rays/s)\n",
                   stats.interrupted ? "Interrupted after" : "Rendered", stats.spp_done,
                   stats.spp_requested, stats.seconds,
                   stats.seconds > 0 ? double(stats.rays) / stats.seconds * 1e-6 : 0.0);
        for (const auto& f : files) fmt::print(stderr, "wrote {}\n", f);
    }
    return stats.interrupted ? kExitInterrupted : kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"femto: a renderer for time-resolved (transient) light transport"};
    app.set_version_flag("--version", std::string("femto ") + femto::version());
    app.require_subcommand(1);
    femto::LoadOptions opts;

    auto* render = app.add_subcommand("render", "Render a scene");
    std::string scene_path, out_base;
    std::vector<std::string> defines;
    uint32_t spp = 0;
    int threads = 0;
    uint64_t seed = 0;
    bool quiet = false, npy = false;
    render->add_option("scene", scene_path, "Scene file (Mitsuba 0.6 / 3.x XML)")->required();
    render->add_option("-o,--output", out_base,
                       "Output path, without extension or with .exr/.png/.npy (default: scene "
                       "name)");
    render->add_option("-D", defines, "Set a scene parameter: -D name=value (repeatable)");
    render->add_option("--spp", spp, "Samples per pixel (overrides the sampler)")
        ->check(whole_number_in(1, std::numeric_limits<uint32_t>::max()));
    render->add_option("--threads", threads, "Worker threads (default: all cores)")
        ->check(whole_number_in(1, 4096));
    render->add_option("--seed", seed, "Random seed")
        ->check(whole_number_in(0, std::numeric_limits<uint64_t>::max()));
    render->add_option("--plugin-dir", opts.plugin_dirs, "Extra plugin folder (repeatable)");
    render->add_flag("--lenient", opts.lenient,
                     "Warn about unknown/unused parameters instead of failing");
    render->add_flag("-q,--quiet", quiet, "No progress or summary output");
    render->add_flag("--npy", npy,
                     "Transient films: also write OUTBASE.npy (float32 [H, W, T, C])");

    auto* plugins = app.add_subcommand("plugins", "List plugins, or print one plugin's parameters");
    std::string plugin_name;
    bool markdown = false;
    plugins->add_option("name", plugin_name, "Plugin type name");
    plugins->add_option("--plugin-dir", opts.plugin_dirs, "Extra plugin folder (repeatable)");
    plugins->add_flag("--markdown", markdown, "Print the reference in Markdown (docs/plugins.md)");
    CLI::App* viz = femto::cli::add_viz_command(app);

    try {
        app.parse(argc, argv);
    } catch (const CLI::Success& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        // Usage errors read like every other femto error; the help text stays one --help away.
        std::fprintf(stderr, "femto: error: %s (see femto --help)\n", e.what());
        return kExitBadInput;
    }
    try {
        if (render->parsed())
            return cmd_render(scene_path, out_base, defines, spp, threads, seed, quiet, npy, opts);
        if (plugins->parsed()) return cmd_plugins(plugin_name, markdown, opts);
        if (viz->parsed()) return femto::cli::run_viz_command();
    } catch (const femto::SceneError& e) {
        std::fprintf(stderr, "femto: error: %s\n", e.what());
        return kExitBadInput;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "femto: internal error: %s\n", e.what());
        return kExitInternal;
    }
    return kExitInternal;
}
