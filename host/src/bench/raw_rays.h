// `femto bench` <raw_rays>: Embree's own ray rate in a scene's geometry, the yardstick for the
// renderer's ray throughput (docs/bench.md).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "femto/math.h"
#include "femto/scene.h"

namespace femto::detail {
class EmbreeScene;
}

namespace femto::bench {

/// Random rays traced by Embree alone (rtcIntersect1 / rtcOccluded1 in a TBB loop, nothing
/// else per ray) in a second BVH built from the scene's shapes by the renderer's own
/// construction (detail::EmbreeScene: same geometry, build quality and flags).
class RawRays {
public:
    enum class Kind {
        incoherent,  ///< origin uniform by area on the surfaces, direction uniform on the
                     ///< hemisphere
        sorted,      ///< the same rays ordered along a Morton curve of their origins
        shadow,      ///< from the same kind of origins to uniform points on the area lights
    };
    struct Rate {
        uint64_t rays = 0;
        double seconds = 0, cpu_seconds = 0;
    };

    /// Generates `count` rays of each kind (untimed). `scene` must outlive this object. Throws
    /// std::runtime_error when the scene has no visible surface.
    RawRays(const Scene& scene, size_t count, uint64_t seed);
    ~RawRays();
    /// Traces the rays of `kind` in passes until `min_seconds` have passed (at least one), on at
    /// most `threads` threads (0: all cores).
    Rate trace(Kind kind, int threads, double min_seconds) const;
    /// False when the scene has no area light (no shadow rays then).
    bool has_shadow_rays() const { return !shadow_.empty(); }

private:
    struct CompactRay {  // 28 bytes, expanded into Embree's ray when traced
        Vec3 o, d;
        float tmax;
    };
    std::unique_ptr<detail::EmbreeScene> embree_;
    std::vector<CompactRay> incoherent_, sorted_, shadow_;
};

const char* kind_name(RawRays::Kind kind);

}  // namespace femto::bench
