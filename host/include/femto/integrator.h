// femto public API: integrators. The host's renderer runs passes and, in each, calls
// sample() once per camera sample (over image tiles) or, for an integrator whose samples start
// at the lights, sample_light() once per light path; the integrator reports each radiance
// contribution with its optical path length (so the same integrator feeds steady and transient
// films), at its camera sample's pixel or, as a splat, at any film position.
// docs/writing-plugins.md explains splatting and the per-pass hook.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "femto/accumulator.h"
#include "femto/film.h"
#include "femto/math.h"
#include "femto/object.h"
#include "femto/sampler.h"
#include "femto/scene.h"

namespace femto {

/// Where an integrator's samples start.
enum class SampleSource {
    /// sample() once per camera sample: samples_per_pixel per pixel, over image tiles.
    Camera,
    /// sample_light() samples_per_pixel x pixels times per render, each adding splats only (a
    /// light tracer has no camera samples). The film normalises the splats by the filter
    /// weight that as many camera samples would carry (Film::add_splat_weight()).
    Light,
};

/// The pass the renderer is about to run (Integrator::begin_pass()).
struct PassInfo {
    uint32_t pass = 0;          ///< 0, 1, ...
    uint64_t seed = 0;          ///< the render's seed (another one for a pilot pass)
    uint32_t sample_begin = 0;  ///< the pass draws sample indices [sample_begin, sample_end)
    uint32_t sample_end = 0;    ///< of every pixel (or light paths sample index x pixels)
    bool pilot = false;         ///< a temporal filter's pilot pass, not part of the image
};

class Integrator : public Object {
public:
    PluginKind kind() const override { return PluginKind::Integrator; }
    /// Called once before rendering, after the scene is built.
    virtual void preprocess(const Scene& /*scene*/) {}
    /// Where this integrator's samples start (default: at the camera).
    virtual SampleSource source() const { return SampleSource::Camera; }
    /// True when sample() adds splats (ContributionList::splat()); light tracers always do.
    /// The renderer then collects them and merges them into the film in a fixed order.
    virtual bool splats() const { return source() == SampleSource::Light; }
    /// Called once before each pass, from one thread, after the film's start_pass() (e.g. a
    /// photon pass that the pass's samples then query; it may use TBB itself).
    virtual void begin_pass(const Scene& /*scene*/, const PassInfo& /*pass*/) {}
    /// Samples per pixel in each pass, when the integrator needs a fixed number (a progressive
    /// photon mapper's iteration is one photon pass and one camera sample per pixel); 0 (the
    /// default) lets the renderer choose.
    virtual uint32_t samples_per_pass() const { return 0; }
    /// How far in time (optical length) the integrator's own kernel may move a contribution
    /// (Contribution::kernel: a density estimator's largest time bandwidth); 0 by default.
    /// Scene::time_window() extends the film's window by it, so that light arriving just after
    /// the window's end is still traced and spread into the last bins. Read before each pass.
    virtual double time_reach() const { return 0.0; }
    /// Names of the extra per-sample channels (AOVs) this integrator reports through
    /// ContributionList::set_aov(), in order; empty (the default) for none. The renderer asks
    /// the film to record them (Film::prepare_aovs()), which fails for films without AOVs;
    /// hdrfilm writes each as a named EXR channel ("layer.X" names group into layers). Only
    /// camera samples carry AOVs: an integrator that declares them must not splat.
    virtual std::vector<std::string> aov_names() const { return {}; }
    /// Estimates the radiance arriving along the camera ray `ray` (unit direction). Camera
    /// integrators implement it; the default throws std::logic_error.
    virtual void sample(const Scene& scene, Sampler& sampler, const Ray& ray,
                        ContributionList& out) const;
    /// Traces one light path and adds what the camera sees of it to `out` (SampleSource::Light
    /// integrators implement it; the default throws std::logic_error). The sampler is started
    /// for (seed, path index modulo pixels, path index / pixels).
    virtual void sample_light(const Scene& scene, Sampler& sampler, SplatList& out) const;
    /// Writes outputs of the integrator's own next to the film's (e.g. debugging images named
    /// `out_base` + a suffix), atomically, and returns the paths written; the default writes
    /// nothing. Called by `femto render` after the film has written its outputs.
    virtual std::vector<std::string> write(const std::string& /*out_base*/,
                                           const RenderInfo& /*info*/) const {
        return {};
    }
    /// The arrays of running totals behind what write() writes (e.g. per-strategy images),
    /// which a distributed render combines across processes before rank 0 writes
    /// (femto/accumulator.h). The default lists none: an integrator that writes images of its
    /// own must list their totals here, or its images hold rank 0's samples only.
    virtual std::vector<Accumulator> accumulators() { return {}; }
};

/// Base of integrators that follow paths of bounded depth (Mitsuba's MonteCarloIntegrator):
/// reads `max_depth`, `rr_depth` and `hide_emitters`, so that every such integrator spells them
/// the same way.
class MonteCarloIntegrator : public Integrator {
public:
    /// max_depth, rr_depth (default 5; a plugin lists its own entry to change that) and
    /// hide_emitters.
    static std::vector<ParamSpec> inherited_params();
    /// Longest path in segments (1 = emitters seen directly, 2 = direct light); -1 = none.
    int64_t max_depth() const { return max_depth_; }
    /// Depth from which Russian roulette may end paths; 0 = never.
    int64_t rr_depth() const { return rr_depth_; }
    /// Whether emitters seen directly by the camera are left out.
    bool hide_emitters() const { return hide_emitters_; }
    /// True when a path with `depth` segments may not be extended.
    bool depth_exhausted(int64_t depth) const { return max_depth_ >= 0 && depth >= max_depth_; }
    /// Russian roulette for a path of `depth` segments that can still carry at most `gain` of
    /// what it started with: from rr_depth() on it survives with probability
    /// q = min(gain, 0.95), drawing one number. Returns the factor its weight takes: 1 / q when
    /// it survives (1 before rr_depth()), 0 when it ends.
    float roulette(int64_t depth, float gain, Sampler& sampler) const {
        if (rr_depth_ <= 0 || depth < rr_depth_) return 1.f;
        const float q = std::min(gain, 0.95f);
        return sampler.next_1d() < q ? 1.f / q : 0.f;
    }
    /// Refuses unbounded paths (max_depth -1 and no roulette) without a finite time window:
    /// nothing would end them.
    void preprocess(const Scene& scene) override;

protected:
    /// `default_rr_depth` is the plugin's default for rr_depth (0: no roulette).
    MonteCarloIntegrator(const Properties& props, int64_t default_rr_depth);

private:
    int64_t max_depth_ = -1, rr_depth_ = 0;
    bool hide_emitters_ = false;
    SourceLocation location_;  // of max_depth (or of the integrator), for preprocess' error
};

}  // namespace femto
