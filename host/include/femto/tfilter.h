// femto public API: temporal reconstruction (<tfilter> inside a transient or streak film):
// how a contribution at time t is spread over the film's time bins (thesis ch. 5.4-5.5).
#pragma once

#include <cstdint>
#include <vector>

#include "femto/object.h"
#include "femto/time.h"

namespace femto {

struct BinWeight {
    int bin;
    float weight;  ///< fraction of the contribution that lands in `bin`
};

class TemporalFilter : public Object {
public:
    PluginKind kind() const override { return PluginKind::TemporalFilter; }
    /// Appends the bins a unit contribution at time t reaches, for pixel `pixel` (index
    /// y * width + x), with the integral of the kernel over each bin. Weights sum to the part
    /// of the kernel inside the window (1 for a histogram when t is inside it).
    virtual void splat(const TimeGrid& grid, uint64_t pixel, double t,
                       std::vector<BinWeight>& out) const = 0;
    /// Called before render pass `pass` (0, 1, ...) starts; progressive kernels shrink here.
    virtual void start_pass(uint32_t /*pass*/) {}
    /// How far (in time) a contribution may spread from t; 0 for a histogram.
    virtual double max_radius() const { return 0.0; }
};

}  // namespace femto
