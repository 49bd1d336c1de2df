// `femto bench` experiments (docs/bench.md): what an experiment file declares, and its reader.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "femto/error.h"

namespace femto::bench {

using Defines = std::vector<std::pair<std::string, std::string>>;

/// One scene of the experiment: a scene file (relative to the experiment file) and the -D
/// values every variant renders it with.
struct SceneSpec {
    std::string name;  ///< `name`, or the file's folder name
    std::string file;  ///< resolved path
    Defines defines;
    SourceLocation location;
};

/// One way of rendering: -D values on top of the scene's, and plugin folders searched first
/// (an out-of-tree integrator joins through them).
struct Variant {
    std::string name;
    Defines defines;
    std::vector<std::string> plugin_dirs;
    SourceLocation location;
};

/// The reference every run is measured against: a file (.npy cube [H, W, T, C] or .exr image),
/// or `variant` rendered at `spp` samples (seed `seed`), rendered once and cached: per scene, or
/// of the one `scene` for every scene (a scene at several scales against its unit scale).
struct ReferenceSpec {
    std::string file;
    std::string variant;
    std::string scene;  ///< empty: each scene's own
    uint32_t spp = 0;
    uint64_t seed = 0;
    SourceLocation location;
};

/// A time window of the error measures: bins whose centre is in [start, end) (scene units).
struct Window {
    std::string name;
    double start = 0, end = 0;
};

/// A pixel whose time profile is measured on its own (thesis Fig. 5.5: one pixel over time).
struct PixelSpec {
    std::string name;
    int x = 0, y = 0;  ///< film pixel (0, 0 is the top left)
    SourceLocation location;
};

struct Experiment {
    std::string file;  ///< the experiment file
    std::string name;
    std::vector<SceneSpec> scenes;
    std::vector<Variant> variants;
    std::vector<uint32_t> spp_budgets;  ///< either these ...
    std::vector<double> time_budgets;   ///< ... or wall-clock seconds per run
    std::vector<uint64_t> seeds;
    ReferenceSpec reference;
    std::vector<Window> windows;
    std::vector<PixelSpec> pixels;
    /// The errors the report fits, each in its own table: "relmse" (the default when none is
    /// given), "pixel_relmse", "frame_relmse", "window:NAME" or "pixel:NAME" (results.csv
    /// columns). The plot shows the first.
    std::vector<std::string> metrics;
    /// Each run in a child process (its peak memory is then measured), not in this one.
    bool child_processes = false;
    /// <raw_rays seconds="..."/>: Embree's raw ray rate measured before each (budget, seed)
    /// group of runs, each kind of ray for at least this long; 0: not measured.
    double raw_rays_seconds = 0;
    int threads = 0;  ///< 0: all cores
    /// Of everything but <seeds> and <budgets> (whitespace and comments aside): rows measured
    /// under another digest are not resumed.
    std::string digest;

    const Variant* find_variant(const std::string& name) const;
    /// The scene whose reference `scene`'s runs are measured against.
    const SceneSpec& reference_scene(const SceneSpec& scene) const;
    /// The budgets in the order they run, as text ("16" spp or "2.5" s).
    std::vector<std::string> budget_labels() const;
    bool timed() const { return !time_budgets.empty(); }
    /// Without a reference, a study measures throughput (and memory) only.
    bool has_reference() const { return !reference.file.empty() || !reference.variant.empty(); }
};

/// Reads an experiment file; bad input is a SceneError at its file:line:col.
Experiment load_experiment(const std::string& path);

/// FNV-1a 64-bit of `bytes`, as 16 hex digits (cache keys, the experiment digest).
std::string digest_hex(const std::string& bytes);

}  // namespace femto::bench
