// femto public API: loading and rendering scenes from C++ (what the `femto` CLI, the tests
// and embedding applications use).
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "femto/film.h"
#include "femto/object.h"
#include "femto/plugin.h"
#include "femto/properties.h"
#include "femto/scene.h"

namespace femto {

struct LoadOptions {
    /// `-D name=value` overrides for `<default>` parameters.
    std::vector<std::pair<std::string, std::string>> defines;
    /// Extra plugin folders (`--plugin-dir`), searched first, in order: their plugins replace
    /// built-in ones of the same type. Each must be an existing folder.
    std::vector<std::string> plugin_dirs;
    /// Report unread parameters as warnings instead of errors.
    bool lenient = false;
};

/// Loads a scene file. Throws SceneError (bad input) with a file:line:col location.
std::unique_ptr<Scene> load_scene(const std::string& path, const LoadOptions& options = {});
/// Loads a scene from XML text; `base_dir` resolves relative file names.
std::unique_ptr<Scene> load_scene_string(const std::string& xml, const LoadOptions& options = {},
                                         const std::string& base_dir = ".");

/// Instantiates one plugin directly (for tests and tools): checks the schema and unread
/// parameters exactly as the loader does.
ObjectPtr create_object(PluginKind kind, const std::string& type, const Properties& props,
                        const LoadOptions& options = {});

/// Descriptor of plugin `type` of `kind`, loading it on first use. Throws SceneError.
const PluginDescriptor& find_plugin(PluginKind kind, const std::string& type,
                                    const LoadOptions& options = {});
/// Every plugin type on the search path with the library that provides it (the first one
/// found; this loads them all).
std::vector<std::pair<std::string, const PluginDescriptor*>> list_plugins(
    const LoadOptions& options = {});
/// Paths of the plugin libraries opened so far (lazy loading means: only those named).
std::vector<std::string> loaded_plugin_files();
/// The folders searched for plugins, in order.
std::vector<std::string> plugin_search_path(const LoadOptions& options = {});

/// The processes of a distributed render (MPI; docs/distributed.md), as the renderer sees
/// them: pass p of the render runs in process p % size(), so that every sample is the one a
/// single process would draw; each process renders into its own film, whose totals
/// (Film::accumulators()) are combined afterwards.
class PassGroup {
public:
    virtual ~PassGroup() = default;
    virtual int rank() const = 0;  ///< this process: 0 .. size() - 1
    virtual int size() const = 0;
    /// Called by every process after each round of passes (one pass per process): true when
    /// `stop` is true in any of them, so that all stop after the same round.
    virtual bool any(bool stop) = 0;
};

struct RenderOptions {
    uint32_t spp = 0;  ///< 0 = the sampler's sample_count
    int threads = 0;   ///< 0 = all cores
    uint64_t seed = 0;
    bool progress = false;   ///< progress line on stderr
    std::string scene_file;  ///< recorded in the outputs
    /// When set and becomes true, rendering stops within the current pass (within a few
    /// samples' work); for an integrator that splats from camera samples (bdpt), at the end of
    /// the current pass; in a distributed render, at the end of the current round of passes.
    const std::atomic<bool>* stop = nullptr;
    /// The processes sharing this render's passes; null: this process renders every pass.
    PassGroup* group = nullptr;
    /// Progress as one line per round of passes (for logs, e.g. a batch job's output) instead
    /// of the redrawn bar; only with `progress`.
    bool progress_lines = false;
};

struct RenderStats {
    uint32_t spp_done = 0;
    uint32_t spp_requested = 0;
    double seconds = 0;
    double pilot_seconds = 0;  ///< of `seconds`: a temporal filter's pilot pass
    /// A temporal filter's pilot that was the image's first samples: how many per pixel (its
    /// time is image time, not in pilot_seconds).
    uint32_t pilot_image_spp = 0;
    uint64_t rays = 0;
    /// Camera samples taken over the image: pixels x spp_done, fewer with adaptive sampling
    /// (Bsdf::pixel_sample_share()).
    uint64_t camera_samples = 0;
    /// Adaptive sampling took a count of samples per pixel (camera_samples / pixels on
    /// average) from the materials the pixels see first.
    bool adaptive = false;
    bool interrupted = false;
    /// What the film refused over its life (every render into it), by reason.
    RejectedContributions rejected;
};

/// Renders into the sensor's film (passes over tiles, TBB threads, deterministic for a
/// given seed and thread count).
RenderStats render(Scene& scene, const RenderOptions& options);
/// RenderInfo for the film's write(), from a finished render.
RenderInfo make_render_info(const Scene& scene, const RenderOptions& options,
                            const RenderStats& stats);

const char* version();

}  // namespace femto
