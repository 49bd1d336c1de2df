#include "femto/time.h"

#include <fmt/format.h>

#include <cmath>

namespace femto {

namespace {
constexpr struct {
    const char* name;
    double metres;
} kUnits[] = {{"km", 1e3}, {"m", 1.0}, {"cm", 1e-2}, {"mm", 1e-3}, {"um", 1e-6}, {"nm", 1e-9}};
constexpr int kMaxBins = 1 << 20;
}  // namespace

const char* time_frame_name(TimeFrame frame) {
    switch (frame) {
        case TimeFrame::Camera:
            return "camera";
        case TimeFrame::World:
            return "world";
        case TimeFrame::Unknown:
            break;
    }
    return "";
}

TimeFrame parse_time_frame(const std::string& name) {
    if (name == "camera") return TimeFrame::Camera;
    if (name == "world") return TimeFrame::World;
    return TimeFrame::Unknown;
}

double TimeGrid::metres_per_unit() const {
    for (const auto& u : kUnits)
        if (length_unit == u.name) return u.metres;
    return 0.0;
}

double TimeGrid::to_picoseconds(double time) const {
    const double m = metres_per_unit();
    if (!(m > 0)) throw SceneError("picoseconds need the film's length_unit");
    return time * m / kSpeedOfLight * 1e12;
}

double TimeGrid::from_picoseconds(double ps) const {
    const double m = metres_per_unit();
    if (!(m > 0)) throw SceneError("picoseconds need the film's length_unit");
    return ps * 1e-12 * kSpeedOfLight / m;
}

std::vector<ParamSpec> time_grid_params() {
    return {{"start", "float", "0", "start of the time window (optical path length, scene units)"},
            {"bin_width", "float", "", "width of a time bin (scene units); or give bin_width_ps"},
            {"bins", "integer", "", "number of time bins"},
            {"start_ps", "float", "", "start of the window in picoseconds (needs length_unit)"},
            {"bin_width_ps", "float", "", "bin width in picoseconds (needs length_unit)"},
            {"length_unit", "string", "", "what one scene unit is: m, cm, mm, um, nm or km"}};
}

TimeGrid read_time_grid(const Properties& props) {
    TimeGrid g;
    g.length_unit = props.get_string("length_unit", "");
    if (!g.length_unit.empty() && !(g.metres_per_unit() > 0))
        props.fail("length_unit",
                   fmt::format("length_unit must be one of km, m, cm, mm, um, nm, not \"{}\"",
                               g.length_unit));
    const bool ps = props.has("start_ps") || props.has("bin_width_ps");
    if (ps && g.length_unit.empty())
        props.fail(props.has("start_ps") ? "start_ps" : "bin_width_ps",
                   "times in picoseconds need length_unit (what one scene unit is, e.g. \"m\")");
    if (props.has("start") && props.has("start_ps"))
        props.fail("start_ps", "give start or start_ps, not both");
    if (props.has("bin_width") && props.has("bin_width_ps"))
        props.fail("bin_width_ps", "give bin_width or bin_width_ps, not both");
    g.start = props.has("start_ps") ? g.from_picoseconds(props.get_float("start_ps"))
                                    : props.get_float("start", 0.0);
    if (props.has("bin_width_ps"))
        g.bin_width = g.from_picoseconds(props.get_float("bin_width_ps"));
    else if (props.has("bin_width"))
        g.bin_width = props.get_float("bin_width");
    else
        props.fail("bin_width",
                   "the film needs a bin width: bin_width (scene units) or bin_width_ps");
    if (!(g.bin_width > 0))
        props.fail(props.has("bin_width") ? "bin_width" : "bin_width_ps",
                   "the bin width must be > 0");
    const int64_t bins = props.get_int("bins");
    if (bins < 1 || bins > kMaxBins)
        props.fail("bins", fmt::format("bins must be in [1, {}], got {}", kMaxBins, bins));
    g.bins = int(bins);
    if (!std::isfinite(g.end())) props.fail("bins", "the time window's end is not finite");
    return g;
}

}  // namespace femto
