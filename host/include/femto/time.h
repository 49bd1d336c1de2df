// femto public API: time conventions (design section 4, docs/units.md).
//
// Time is carried in double precision as optical path length in scene units (time x c; a
// distance d inside a medium of index eta counts as eta * d). Films bin it on a TimeGrid.
#pragma once

#include <string>

#include "femto/properties.h"

namespace femto {

/// Speed of light in vacuum, in metres per second (exact).
inline constexpr double kSpeedOfLight = 299792458.0;

/// Uniform time bins [start + i * bin_width, start + (i + 1) * bin_width), i < bins.
struct TimeGrid {
    double start = 0.0;
    double bin_width = 1.0;
    int bins = 1;
    std::string length_unit;  ///< "m", "cm", "mm", "um", "nm", "km" or "" (unknown)

    double end() const { return start + bin_width * bins; }
    /// Bin holding time t, or -1 outside the window.
    int bin_of(double t) const {
        if (!(t >= start) || !(t < end())) return -1;
        const int b = int((t - start) / bin_width);
        return b < bins ? b : bins - 1;
    }
    /// Metres per scene unit for length_unit, or 0 when it is unknown.
    double metres_per_unit() const;
    /// Path length (scene units) <-> picoseconds, given length_unit (throws if unknown).
    double to_picoseconds(double path_length) const;
    double from_picoseconds(double ps) const;
};

/// The time a film records for a contribution of optical path length `path_length`: camera
/// time is the whole path; world time (eq. 4.1) removes the sensor segment (the camera
/// sample's sensor distance; nothing is removed when the camera ray escaped, distance < 0).
inline double recorded_time(double path_length, double sensor_distance, bool world_time) {
    return world_time && sensor_distance > 0 ? path_length - sensor_distance : path_length;
}

/// Reads a film's time window: `start`, `bin_width`, `bins` in scene units, or `start_ps` and
/// `bin_width_ps` in picoseconds together with `length_unit`. Throws located SceneErrors.
TimeGrid read_time_grid(const Properties& props);

/// The parameters read_time_grid() reads, for the schema of the film that calls it.
std::vector<ParamSpec> time_grid_params();

}  // namespace femto
