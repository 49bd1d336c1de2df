// `femto btf synth` writes the synthetic BTFs of docs/btf.md (closed forms for every filtering
// the BTF material does); `femto btf info` prints what a BTF file holds.
#include "btf.h"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <filesystem>

#include "btf/synth.h"
#include "femto/btf.h"
#include "femto/btf_prefilter.h"
#include "femto/error.h"
#include "output_folder.h"

namespace fs = std::filesystem;

namespace femto::cli {

namespace {

struct SynthArgs {
    std::string output, kind = "harmonic", format = "bdi", sampling = "ubo2003";
    uint32_t width = 64, height = 64;
    int color_model = 0;
    double slope = 35;
    bool half = false, cosine_flag = false;
} g_synth;
std::string g_info_file;
struct PrefilterArgs {
    bool show = false, no_cache = false;
    uint32_t components = 16;
    std::string filter = "box";
} g_prefilter;
CLI::App *g_btf = nullptr, *g_synth_cmd = nullptr, *g_info_cmd = nullptr;

btf::Format parse_format(const std::string& name) {
    if (name == "bdi") return btf::Format::Bdi;
    if (name == "dfmf") return btf::Format::Dfmf;
    return btf::Format::Fmf;
}

int run_synth() {
    btf::synth::Options o;
    o.kind = g_synth.kind == "vgroove" ? btf::synth::Kind::VGroove : btf::synth::Kind::Harmonic;
    // CLI::Range lets NaN through (every comparison with it is false).
    if (!(g_synth.slope >= 1 && g_synth.slope <= 89))
        throw SceneError(
            fmt::format("--slope must be from 1 to 89 degrees, got {}", g_synth.slope));
    o.vgroove_slope_deg = g_synth.slope;
    o.format = parse_format(g_synth.format);
    o.width = g_synth.width;
    o.height = g_synth.height;
    o.directions =
        g_synth.sampling == "ubo2014" ? btf::ubo2014_directions() : btf::ubo2003_directions();
    o.color_model = g_synth.color_model;
    o.half = g_synth.half;
    o.cosine_flag = g_synth.cosine_flag;
    if (o.color_model == btf::kColorLogYuv && o.format != btf::Format::Dfmf)
        throw SceneError("--color-model 11 (log-YUV) is written for --format dfmf only");
    if (o.kind == btf::synth::Kind::VGroove &&
        (o.format == btf::Format::Fmf || o.color_model != btf::kColorRgb))
        throw SceneError("--kind vgroove is written as --format bdi or dfmf, colour model 0");
    const uint64_t n = o.directions.size();
    const uint64_t bytes = uint64_t(o.width) * o.height * n * n * 3 * 2;
    if (o.format == btf::Format::Bdi && bytes > (uint64_t(4) << 30))
        throw SceneError(
            fmt::format("a {}x{} BDI of {} directions would take {:.1f} GB; use "
                        "--format dfmf or a smaller texture",
                        o.width, o.height, n, double(bytes) / (1 << 30)));
    prepare_output_folder(fs::path(g_synth.output).parent_path());  // as render and viz do
    btf::synth::write(g_synth.output, o);
    fmt::print(stderr, "wrote {} ({} {}x{}, {} light x {} view directions)\n", g_synth.output,
               btf::format_name(o.format), o.width, o.height, n, n);
    return 0;
}

/// The number of leading singular values that hold `share` of the energy.
size_t components_for(const std::vector<double>& sigma, double share) {
    double total = 0, kept = 0;
    for (double s : sigma) total += s * s;
    for (size_t i = 0; i < sigma.size(); ++i) {
        kept += sigma[i] * sigma[i];
        if (kept >= share * total) return i + 1;
    }
    return sigma.size();
}

void print_prefilter(const btf::Data& data) {
    btf::PrefilterSettings settings;
    settings.kernel = g_prefilter.filter == "gaussian"  ? btf::FilterKernel::Gaussian
                      : g_prefilter.filter == "lanczos" ? btf::FilterKernel::Lanczos
                                                        : btf::FilterKernel::Box;
    btf::PcaSettings pca;
    pca.components = g_prefilter.components;
    btf::PrefilterReport report;
    const auto h =
        btf::prefiltered(g_info_file, data, settings, pca, !g_prefilter.no_cache, report);
    fmt::print("prefilter:   {} filter, {} levels x {} x {} cones, {:.1f} MB, {} in {:.2f} s\n",
               g_prefilter.filter, h->levels(), h->cone_count(), h->cone_count(),
               double(report.memory_bytes) / (1 << 20),
               report.from_cache ? "loaded from " + report.cache_file : "built", report.seconds);
    if (!report.cache_problem.empty())
        fmt::print("cache:       not written: {}\n", report.cache_problem);
    if (report.factorized)
        fmt::print("PCA:         k = {}: energy kept {:.5f} {:.5f} {:.5f} (R G B)\n",
                   h->components(), report.pca.energy_kept[0], report.pca.energy_kept[1],
                   report.pca.energy_kept[2]);
    fmt::print("level  texels      components for 99% / 99.9% of the energy (R G B)\n");
    for (int level = 0; level < h->levels(); ++level) {
        fmt::print("{:5}  {:>5} x {:<5}", level, h->width(level), h->height(level));
        for (double share : {0.99, 0.999}) {
            fmt::print(" ");
            for (int c = 0; c < 3; ++c)
                fmt::print(" {:3}", components_for(h->level_spectrum(level, c), share));
        }
        fmt::print("\n");
    }
}

int run_info() {
    const auto data = btf::read(g_info_file);
    const btf::Header& h = data->header();
    fmt::print("file:        {}\n", g_info_file);
    fmt::print("format:      {}\n", btf::format_name(h.format));
    fmt::print("texels:      {} x {}\n", h.width, h.height);
    fmt::print("directions:  {} lights x {} views\n", h.light_count(), h.view_count());
    fmt::print("colour:      {}\n",
               h.color_model == btf::kColorLogYuv ? "11 (log-YUV)" : "0 (RGB)");
    fmt::print("cosine flag: {}\n", h.cosine_flag ? "yes (divided out)" : "no");
    if (data->components() > 0) fmt::print("components:  {}\n", data->components());
    fmt::print("memory:      {:.1f} MB\n", double(data->memory_bytes()) / (1 << 20));
    fmt::print("setup:       {}\n", h.measurement_setup);
    if (g_prefilter.show) print_prefilter(*data);
    return 0;
}

}  // namespace

CLI::App* add_btf_command(CLI::App& app) {
    g_btf = app.add_subcommand("btf",
                               "BTF files: synthetic BTFs (synth) and a file's header "
                               "(info). See docs/btf.md.");
    g_btf->require_subcommand(1);
    g_synth_cmd = g_btf->add_subcommand(
        "synth", "Write a synthetic BTF whose filtering has closed forms (docs/btf.md)");
    g_synth_cmd->add_option("-o,--output", g_synth.output, "Output file")->required();
    g_synth_cmd
        ->add_option("--kind", g_synth.kind,
                     "harmonic: BTF A, rank 3 per channel; vgroove: BTF B, Lambertian V-grooves")
        ->check(CLI::IsMember({"harmonic", "vgroove"}));
    g_synth_cmd->add_option("--slope", g_synth.slope, "vgroove: facet slope in degrees")
        ->check(CLI::Range(1.0, 89.0));
    g_synth_cmd->add_option("--format", g_synth.format, "bdi, dfmf or fmf")
        ->check(CLI::IsMember({"bdi", "dfmf", "fmf"}));
    g_synth_cmd
        ->add_option("--sampling", g_synth.sampling, "ubo2003 (81 directions) or ubo2014 (151)")
        ->check(CLI::IsMember({"ubo2003", "ubo2014"}));
    g_synth_cmd->add_option("--width", g_synth.width, "Texels across")->check(CLI::Range(1, 4096));
    g_synth_cmd->add_option("--height", g_synth.height, "Texels down")->check(CLI::Range(1, 4096));
    g_synth_cmd
        ->add_option("--color-model", g_synth.color_model,
                     "DFMF colour model: 0 (RGB) or 11 (log-YUV)")
        ->check(CLI::IsMember({0, 11}));
    g_synth_cmd->add_flag("--half", g_synth.half, "DFMF/FMF matrices as half floats");
    g_synth_cmd->add_flag("--cosine-flag", g_synth.cosine_flag,
                          "Store B cos(theta_light) and set the file's cosine flag");
    g_info_cmd = g_btf->add_subcommand("info", "Print what a BTF file holds");
    g_info_cmd->add_option("file", g_info_file, "BTF file (BDI, DFMF, FMF)")->required();
    g_info_cmd->add_flag("--prefilter", g_prefilter.show,
                         "Build (or load) the prefiltered hierarchy and print, per level, the "
                         "components its energy needs");
    g_info_cmd
        ->add_option("--components", g_prefilter.components,
                     "PCA components for files without linear factors (BDI, log data)")
        ->check(CLI::Range(1, 512));
    g_info_cmd->add_option("--filter", g_prefilter.filter, "box, gaussian or lanczos")
        ->check(CLI::IsMember({"box", "gaussian", "lanczos"}));
    g_info_cmd->add_flag("--no-cache", g_prefilter.no_cache,
                         "Neither read nor write the hierarchy's cache file");
    return g_btf;
}

int run_btf_command() {
    if (g_synth_cmd->parsed()) return run_synth();
    return run_info();
}

}  // namespace femto::cli
