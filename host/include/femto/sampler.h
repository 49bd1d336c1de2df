// femto public API: pixel samplers (sources of the random numbers a path consumes).
#pragma once

#include <cstdint>
#include <memory>

#include "femto/math.h"
#include "femto/object.h"
#include "femto/properties.h"

namespace femto {

class Sampler : public Object {
public:
    PluginKind kind() const override { return PluginKind::Sampler; }

    /// A fresh sampler of the same type and settings, for one worker thread.
    virtual std::unique_ptr<Sampler> clone() const = 0;
    /// Positions the sampler at sample `sample_index` of pixel `pixel_index` for the render
    /// seed `seed`. The numbers drawn afterwards depend only on these three values, which is
    /// what makes renders deterministic whatever the thread scheduling.
    virtual void start(uint64_t seed, uint64_t pixel_index, uint32_t sample_index) = 0;
    virtual float next_1d() = 0;
    virtual Vec2 next_2d() = 0;

    /// The dimension the next next_1d() or next_2d() opens: 0 after start(), one more per
    /// draw. A sampler whose dimensions are all alike (`independent`) may keep it at 0.
    virtual uint64_t dimension() const { return 0; }
    /// Skips ahead to dimension `d` (nothing when the sampler is at or past it: a dimension is
    /// never drawn twice in a sample). An integrator whose number of draws varies from sample
    /// to sample (BDPT: subpaths of different lengths) starts each decision at a fixed
    /// dimension this way, so that a stratified or low-discrepancy sampler stratifies that
    /// decision over the pixel's samples. The default does nothing: independent numbers need
    /// no alignment.
    virtual void advance_to(uint64_t d) { (void)d; }

    uint32_t sample_count() const { return sample_count_; }
    void set_sample_count(uint32_t n) { sample_count_ = n; }

    /// `sample_count` and `seed`: what the constructor reads, for the plugin schemas.
    static std::vector<ParamSpec> inherited_params();

protected:
    Sampler() = default;
    /// Reads the parameters every sampler takes: `sample_count` (a positive integer below
    /// 2^32, default 4) and `seed` (default 0, combined with the render's seed).
    explicit Sampler(const Properties& props);

    uint32_t sample_count_ = 4;
    uint64_t seed_ = 0;
};

}  // namespace femto
