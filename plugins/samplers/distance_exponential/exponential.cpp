// exponential: distance sampling that spreads path vertices uniformly in time (thesis
// ch. 5.6.1, eq. 5.21-5.23, appendix 5.C.1). For p(r) = lambda e^(-lambda r) the vertex times
// t_i = eta * (r_1 + ... + r_i) of a path have a summed density of exactly lambda / eta per
// unit of optical length, whatever lambda is; lambda only sets how many vertices a path has
// on average before the window ends, lambda * t_e / eta.
//
// The rate is `lambda` (per scene unit of optical length, i.e. of time x c) or, by default,
// derived from `mean_vertices` (default 3; the thesis finds 3-4 a good compromise): lambda =
// mean_vertices / t_e with t_e the end of the film's window. In a medium of index eta the
// rate per unit of distance is lambda * eta (a distance d takes eta * d of time).
#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "femto/error.h"
#include "femto/plugin.h"
#include "femto/time_sampling.h"

namespace {

using namespace femto;

class Exponential final : public DistanceSampler {
public:
    explicit Exponential(const Properties& props) {
        if (props.has("lambda") && props.has("mean_vertices"))
            props.fail("mean_vertices", "give lambda or mean_vertices, not both");
        if (props.has("lambda")) {
            lambda_ = props.get_float("lambda");
            if (!(lambda_ > 0) || !std::isfinite(lambda_))
                props.fail("lambda", "lambda must be positive and finite (1 / scene unit)");
        } else {
            mean_vertices_ = props.get_float("mean_vertices", 3.0);
            if (!(mean_vertices_ > 0) || !std::isfinite(mean_vertices_))
                props.fail("mean_vertices", "mean_vertices must be positive and finite");
        }
    }

    void prepare(const DistanceContext& ctx) const override {
        if (lambda_ == 0 && !(ctx.window_end > 0 && std::isfinite(ctx.window_end)))
            throw SceneError(
                location(),
                "distance sampling \"exponential\" with mean_vertices needs a film with a finite "
                "time window in camera time (a transient or streak film); give lambda instead");
    }

    double rate(const Medium& medium, const DistanceContext& ctx) const override {
        const double per_time = lambda_ > 0 ? lambda_ : mean_vertices_ / ctx.window_end;
        return per_time * medium.eta();
    }

private:
    double lambda_ = 0;  // 0: from mean_vertices
    double mean_vertices_ = 3;
};

}  // namespace

FEMTO_PLUGIN(Exponential, femto::PluginKind::Distance, "exponential",
             "Time-uniform distance sampling (ch. 5.6.1): an exponential whose rate spreads "
             "vertices evenly over the film's time window",
             {{"lambda", "float", "",
               "rate per scene unit of optical length (time x c); instead of mean_vertices"},
              {"mean_vertices", "float", "3",
               "average number of path vertices before the window ends: lambda = "
               "mean_vertices / window end"}})
