// independent: uniform pseudo-random numbers from PCG32 (Mitsuba's `independent` sampler).
//
// start(seed, pixel, sample) seeds a fresh PCG32 from a hash of (sampler seed, render seed,
// pixel, sample), so the numbers of one camera sample depend on nothing else: the render is
// the same whatever order the threads visit the pixels in.
#include <cstdint>
#include <limits>
#include <memory>
#include <string>

#include "femto/plugin.h"
#include "femto/random.h"
#include "femto/sampler.h"

namespace {

class IndependentSampler final : public femto::Sampler {
public:
    explicit IndependentSampler(const femto::Properties& props) : Sampler(props) {}

    std::unique_ptr<femto::Sampler> clone() const override {
        return std::make_unique<IndependentSampler>(*this);
    }

    void start(uint64_t seed, uint64_t pixel_index, uint32_t sample_index) override {
        const uint64_t h = femto::hash_combine(
            femto::hash_combine(femto::hash_combine(seed_, seed), pixel_index), sample_index);
        // The state and the stream come from two different hashes so that neighbouring
        // (pixel, sample) pairs get unrelated generators.
        rng_.seed(h, femto::mix64(h ^ 0x5851f42d4c957f2dULL));
    }

    float next_1d() override { return rng_.next_float(); }
    femto::Vec2 next_2d() override {
        const float x = rng_.next_float();
        const float y = rng_.next_float();
        return {x, y};
    }

private:
    femto::Pcg32 rng_;
};

}  // namespace

FEMTO_PLUGIN(IndependentSampler, femto::PluginKind::Sampler, "independent",
             "Independent uniform random numbers (PCG32 seeded per pixel and sample)", {})
