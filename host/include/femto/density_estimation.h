// femto public API: what progressive density estimators (photon mapping, photon beams;
// thesis ch. 5.5 and appendix 5.B) read and check the same way: their bandwidth schedules and
// initial bandwidths, the default R_1 and T_1, and the film they need.
#pragma once

#include <string>

#include "femto/kernel.h"
#include "femto/properties.h"
#include "femto/scene.h"

namespace femto {

/// Reads `prefix`alpha (in (0, 1)) and `prefix`beta_t (in [0, 1]) with the given defaults, for a
/// spatial kernel of `dims` dimensions; a located SceneError when out of range.
ProgressiveBandwidths read_progressive_schedule(const Properties& props, const std::string& prefix,
                                                double alpha, double beta_t, int dims);

/// Reads an optional bandwidth (a radius or a time half-width, scene units): positive and
/// finite when given (a located SceneError otherwise), 0 when not (the caller's default).
double read_optional_bandwidth(const Properties& props, const std::string& name);

/// The default initial radius R_1: three pixel footprints where the image centre's camera ray
/// meets the scene (the distance between it and the next pixel's ray there), or a mean free
/// path away when the sensor sits in a medium and that is nearer; at most 1/50 of the scene's
/// bounding radius; 1/500 of that radius when the centre ray finds neither (one scene unit in
/// an empty scene). docs/photon-mapping.md explains the choice.
double default_initial_radius(const Scene& scene);

/// The default initial time half-width T_1: two film bins (1 for a steady film, which ignores
/// the kernel).
double default_initial_bandwidth(const Scene& scene);

/// An estimator that smooths time with its own kernel needs a time-resolved film that does not
/// smooth a second time: a located SceneError naming `integrator` unless the film is steady or
/// uses <tfilter type="histogram"/>.
void require_histogram_film(const Scene& scene, const std::string& integrator);

}  // namespace femto
