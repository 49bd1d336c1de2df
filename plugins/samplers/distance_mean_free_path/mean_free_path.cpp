// mean_free_path: steady-state distance sampling, p(r) = sigma e^(-sigma r) with sigma the
// medium's extinction (the mean of sigma_t's channels in a homogeneous medium, the majorant
// in a heterogeneous one, whose transmittance is then ratio-tracked in the path weight).
// It favours short distances where sigma_t is large: vertices crowd at early times.
#include "femto/plugin.h"
#include "femto/time_sampling.h"

namespace {

using namespace femto;

class MeanFreePath final : public DistanceSampler {
public:
    explicit MeanFreePath(const Properties&) {}

    double rate(const Medium& medium, const DistanceContext&) const override {
        return mean_free_path_rate(medium);
    }
};

}  // namespace

FEMTO_PLUGIN(MeanFreePath, femto::PluginKind::Distance, "mean_free_path",
             "Steady distance sampling: an exponential at the medium's extinction (ch. 5.6.1)", {})
