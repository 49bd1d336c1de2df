// line_to_point: time-uniform shadow connections (thesis ch. 5.6.2, eq. 5.24-5.25, appendix
// 5.C.2). On each ray segment through a medium an extra vertex x(r) is placed so that the
// duration of the two-segment connection origin -> x(r) -> light is uniform over the range
// the segment allows: from the straight line (r = 0, eq. 5.110) to the segment's end or the
// film window's end, whichever comes first (eq. 5.111). A segment with no end and no window
// has no finite time range; there the strategy falls back to equiangular sampling.
#include <cmath>

#include "femto/plugin.h"
#include "femto/time_sampling.h"

namespace {

using namespace femto;

class LineToPoint final : public ConnectionSampler {
public:
    explicit LineToPoint(const Properties&) {}

    double sample(const ConnectionQuery& q, double u) const override {
        return std::isfinite(q.length) ? line_to_point_sample(q, u) : equiangular_sample(q, u);
    }
    double pdf(const ConnectionQuery& q, double r) const override {
        return std::isfinite(q.length) ? line_to_point_pdf(q, r) : equiangular_pdf(q, r);
    }
};

}  // namespace

FEMTO_PLUGIN(LineToPoint, femto::PluginKind::Connection, "line_to_point",
             "Time-uniform shadow connections through an extra medium vertex (ch. 5.6.2, "
             "eq. 5.24-5.25)",
             {})
