// Histogram temporal reconstruction: a contribution at time t lands entirely in the bin that
// contains t (thesis ch. 5.4.1), so a bin holds the integral of radiance over its interval
// and a pixel's bins sum to its steady value.
#include "femto/plugin.h"
#include "femto/tfilter.h"

namespace {

using namespace femto;

class Histogram final : public TemporalFilter {
public:
    explicit Histogram(const Properties&) {}

    bool is_histogram() const override { return true; }

    void splat(const TimeGrid& grid, uint64_t, uint32_t, double t,
               std::vector<BinWeight>& out) const override {
        const int bin = grid.bin_of(t);
        if (bin >= 0) out.push_back({bin, 1.f});
    }
};

}  // namespace

FEMTO_PLUGIN(Histogram, femto::PluginKind::TemporalFilter, "histogram",
             "Histogram in time: each contribution lands in the bin holding its time", {})
