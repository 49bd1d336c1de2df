// `femto btf synth` writes the synthetic BTFs of docs/btf.md (closed forms for every filtering
// the BTF material does); `femto btf info` prints what a BTF file holds.
#include "btf.h"

#include <fmt/format.h>

#include <CLI/CLI.hpp>

#include "btf/synth.h"
#include "femto/btf.h"
#include "femto/error.h"

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
CLI::App *g_btf = nullptr, *g_synth_cmd = nullptr, *g_info_cmd = nullptr;

btf::Format parse_format(const std::string& name) {
    if (name == "bdi") return btf::Format::Bdi;
    if (name == "dfmf") return btf::Format::Dfmf;
    return btf::Format::Fmf;
}

int run_synth() {
    btf::synth::Options o;
    o.kind = g_synth.kind == "vgroove" ? btf::synth::Kind::VGroove : btf::synth::Kind::Harmonic;
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
    btf::synth::write(g_synth.output, o);
    fmt::print(stderr, "wrote {} ({} {}x{}, {} light x {} view directions)\n", g_synth.output,
               btf::format_name(o.format), o.width, o.height, n, n);
    return 0;
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
    return g_btf;
}

int run_btf_command() {
    if (g_synth_cmd->parsed()) return run_synth();
    return run_info();
}

}  // namespace femto::cli
