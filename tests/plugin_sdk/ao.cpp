// Ambient occlusion: the fraction of the cosine-weighted hemisphere above the first hit that
// is unoccluded within `max_distance`. An example of a user plugin built with the femto SDK.
#include <femto/integrator.h>
#include <femto/path_clock.h>
#include <femto/plugin.h>
#include <femto/warp.h>

namespace {

class AmbientOcclusion final : public femto::Integrator {
public:
    explicit AmbientOcclusion(const femto::Properties& props) {
        samples_ = props.get_int("samples", 16);
        max_distance_ = float(props.get_float("max_distance", 1e30));
        if (samples_ < 1) props.fail("samples", "samples must be >= 1");
        if (!(max_distance_ > 0)) props.fail("max_distance", "max_distance must be > 0");
    }

    void sample(const femto::Scene& scene, femto::Sampler& sampler, const femto::Ray& ray,
                femto::ContributionList& out) const override {
        // The clock applies femto's time rules: the first vertex's distance is the sensor
        // distance (world-time films and depth need it), and the value lands at its time.
        femto::PathClock clock(scene, out, ray.o);
        femto::Hit hit;
        if (!scene.intersect(ray, hit)) return;
        clock.travel_to(hit.p, 1.0);
        clock.reach_vertex();
        // Occlusion is measured on the side the camera sees.
        const femto::Vec3 n = femto::dot(hit.ng, ray.d) < 0 ? hit.ng : -hit.ng;
        const femto::Frame frame(n);
        int visible = 0;
        for (int64_t i = 0; i < samples_; ++i) {
            const femto::Vec3 d =
                frame.to_world(femto::warp::square_to_cosine_hemisphere(sampler.next_2d()));
            femto::Ray r = hit.spawn(d);
            r.tmax = max_distance_;
            if (!scene.occluded(r)) ++visible;
        }
        clock.record(femto::Color(float(visible) / float(samples_)));
    }

private:
    int64_t samples_;
    float max_distance_;
};

}  // namespace

FEMTO_PLUGIN(AmbientOcclusion, femto::PluginKind::Integrator, "ao",
             "Ambient occlusion (example plugin built with the femto SDK)",
             {{"samples", "integer", "16", "occlusion rays per camera sample"},
              {"max_distance", "float", "1e30", "occluders farther than this are ignored"}})
