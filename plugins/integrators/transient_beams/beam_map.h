// The photon beams of one pass as an Embree scene, for the queries of camera rays: which beams
// pass within R of a ray segment (docs/photon-beams.md).
//
// Beams are Embree round linear curves of constant radius R (a capsule around each segment):
// a ray passes within R of a beam exactly when it hits its capsule. Embree builds its curve
// BVH with oriented bounds around thin segments, which bound a long oblique beam far more
// tightly than the axis-aligned boxes of user geometry would, so a ray visits far fewer
// candidates. Every hit is recorded by a filter callback and rejected, so traversal goes on to
// all of them; a capsule may report two hits (entry and exit), so the beams found are sorted and
// made unique, which also makes the order in which they are summed independent of the BVH.
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <vector>

#include "femto/math.h"

namespace femto_beams {

using femto::Vec3;

class BeamMap {
public:
    BeamMap();
    ~BeamMap();
    BeamMap(const BeamMap&) = delete;
    BeamMap& operator=(const BeamMap&) = delete;

    /// Indexes the segments [starts[i], ends[i]] with capsules of radius `radius` (replaces
    /// the previous pass's). Frees the previous scene first.
    void build(const std::vector<Vec3>& starts, const std::vector<Vec3>& ends, float radius);
    /// Frees the scene.
    void release();
    /// The indices of the beams whose capsule the segment from o along unit direction d over
    /// [0, length] (length may be infinite) passes, ascending, into `found` (cleared first).
    void query(const Vec3& o, const Vec3& d, double length, std::vector<uint32_t>& found) const;

private:
    RTCDevice device_ = nullptr;
    RTCScene scene_ = nullptr;
    float radius_ = 0.f;
};

}  // namespace femto_beams
