// femto public API: time conventions (design section 4, docs/units.md).
//
// Time is carried in double precision as optical path length in scene units (time x c; a
// distance d inside a medium of index eta counts as eta * d). Films bin it on a TimeGrid.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "femto/properties.h"

namespace femto {

/// Speed of light in vacuum, in metres per second (exact).
inline constexpr double kSpeedOfLight = 299792458.0;

/// Which time a film records (design section 4): camera time, the whole path (as a real camera
/// measures it), or world time, the sensor segment removed (eq. 4.1).
enum class TimeFrame { Unknown, Camera, World };

/// "camera", "world" or "" (unknown): the value of an output's femto:time attribute.
const char* time_frame_name(TimeFrame frame);
/// The frame named by time_frame_name(); Unknown for anything else.
TimeFrame parse_time_frame(const std::string& name);

/// Uniform time bins [start + i * bin_width, start + (i + 1) * bin_width), i < bins: a film's
/// time window, or the time axis of a cube read back from a file.
struct TimeGrid {
    double start = 0.0;
    double bin_width = 1.0;
    int bins = 1;
    std::string length_unit;  ///< "m", "cm", "mm", "um", "nm", "km" or "" (unknown)
    TimeFrame frame = TimeFrame::Camera;
    /// False when only bin indices are known (a cube read from a .npy without its start and
    /// bin width): start and bin_width then keep their defaults and the axis counts bins.
    bool known = true;

    double end() const { return start + bin_width * bins; }
    /// True when time t lies in the window [start, end()) (bin_of(t) >= 0), found without
    /// dividing.
    bool contains(double t) const { return t >= start && t < end(); }
    /// Bin holding time t, or -1 outside the window.
    int bin_of(double t) const {
        if (!contains(t)) return -1;
        const int b = int((t - start) / bin_width);
        return b < bins ? b : bins - 1;
    }
    /// Time at the middle of bin `bin`.
    double bin_centre(int bin) const { return start + (bin + 0.5) * bin_width; }
    /// Metres per scene unit for length_unit, or 0 when it is unknown.
    double metres_per_unit() const;
    /// Time (scene units of optical length) <-> picoseconds, given length_unit (throws if
    /// unknown).
    double to_picoseconds(double time) const;
    double from_picoseconds(double ps) const;
};

/// What an integrator needs to know of the film's time window (design section 4): light that
/// reaches the film later than `end` is not recorded, so paths may stop once nothing they can
/// still carry would arrive before it (ch. 5.6.1). Scene::time_window() holds the current one.
struct TimeWindow {
    /// Latest time (optical path length, camera time) the film records: the window's end plus
    /// the temporal filter's reach and the integrator's (Integrator::time_reach()); infinite
    /// for steady films and in world time.
    double end = std::numeric_limits<double>::infinity();
    /// Latest world time the film records (a world-time film's `end`); infinite otherwise. A
    /// camera path learns how much camera time that allows at its first scattering vertex.
    double world_end = std::numeric_limits<double>::infinity();
    /// Earliest emission time of any emitter (PulseProfile::earliest).
    double earliest_emission = 0.0;
    /// Whether the window may cut paths and connections (the film's `prune_paths`, on by
    /// default). Off, paths end only by depth or roulette and connections are never skipped
    /// for time: the image is the same, only slower; it measures what pruning saves. `end`
    /// and `world_end` stay the film's either way (time-sampling strategies spread vertices
    /// over them).
    bool prune = true;
    /// Longest optical length a camera path may have travelled and still bring light to the
    /// film: light leaving an emitter no earlier than earliest_emission must arrive by `end`,
    /// or by world_end after the path's sensor distance `sensor_distance` (negative: unknown
    /// yet, the path has not scattered). Infinite when the window does not prune.
    double path_cut(double sensor_distance = -1.0) const {
        constexpr double kNever = std::numeric_limits<double>::infinity();
        if (!prune) return kNever;
        const double world = sensor_distance >= 0 ? world_end + sensor_distance : kNever;
        return std::min(end, world) - earliest_emission;
    }
    /// Longest time (emission time included) a light path may reach and still be recorded:
    /// the window's end, or its world end (a light path's world time is its own time: the
    /// connection to the sensor is the sensor segment). Infinite when the window does not prune.
    double light_cut() const {
        return prune ? std::min(end, world_end) : std::numeric_limits<double>::infinity();
    }
    /// Whether the window ends every path (camera time, or world time once a path scatters).
    bool bounded() const { return prune && (std::isfinite(end) || std::isfinite(world_end)); }
};

/// The time a film records for a contribution that arrives at camera time `time`: camera
/// time is the whole path; world time (eq. 4.1) removes the sensor segment (the camera
/// sample's sensor distance; nothing is removed when the camera ray escaped, distance < 0).
inline double recorded_time(double time, double sensor_distance, bool world_time) {
    return world_time && sensor_distance > 0 ? time - sensor_distance : time;
}

/// Reads a film's time window: `start`, `bin_width`, `bins` in scene units, or `start_ps` and
/// `bin_width_ps` in picoseconds together with `length_unit` (the frame is left as camera time;
/// films read `world_time` themselves). Throws located SceneErrors.
TimeGrid read_time_grid(const Properties& props);

/// The parameters read_time_grid() reads, for the schema of the film that calls it.
std::vector<ParamSpec> time_grid_params();

}  // namespace femto
