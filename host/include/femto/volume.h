// femto public API: volumes (Mitsuba's <volume>), values over a region of space that media read
// their coefficients from: a voxel grid (`gridvolume`), a constant (`constvolume`).
//
// A volume is given in scene coordinates and is zero outside its region (a grid's box placed by
// its to_world; a constant's region is all of space). Media ask for values at points, for the
// extremes (majorants) and for the part of a ray inside the region (to track only there).
#pragma once

#include <limits>
#include <memory>
#include <string>

#include "femto/color.h"
#include "femto/math.h"
#include "femto/object.h"
#include "femto/properties.h"

namespace femto {

class Volume : public Object {
public:
    PluginKind kind() const override { return PluginKind::Volume; }
    /// 1 (a scalar field, such as a density) or 3 (a colour, such as an albedo).
    virtual int channels() const = 0;
    /// The value at `p` (a 1-channel volume gives it in all three channels); 0 outside the
    /// region.
    virtual Color eval(const Vec3& p) const = 0;
    /// Channel 0 at `p`, in double precision (what media track with); 0 outside the region.
    virtual double eval_1(const Vec3& p) const { return double(eval(p)[0]); }
    /// Smallest and largest values over the region, per channel.
    virtual Color min_value() const = 0;
    virtual Color max_value() const = 0;
    /// True when the value is the same at every point of all space (a constant volume).
    virtual bool is_constant() const { return false; }
    /// Narrows [t0, t1] to the part of the ray o + t d inside the region; false when that part
    /// is empty. The default (an unbounded region) leaves the interval as it is.
    virtual bool clip(const Ray& ray, double& t0, double& t1) const {
        (void)ray;
        return t0 < t1;
    }
    /// Longest straight segment through the region, in scene units (infinite when unbounded).
    virtual double longest_chord() const { return std::numeric_limits<double>::infinity(); }
};

/// The same value everywhere: what a plain `<float>` / `<rgb>` given for a volume parameter
/// becomes, and the `constvolume` plugin.
class ConstantVolume : public Volume {
public:
    /// `channels`: 1 for a scalar (a grey `value`), 3 for a colour.
    ConstantVolume(const Color& value, int channels) : value_(value), channels_(channels) {}
    int channels() const override { return channels_; }
    Color eval(const Vec3&) const override { return value_; }
    double eval_1(const Vec3&) const override { return double(value_[0]); }
    Color min_value() const override { return value_; }
    Color max_value() const override { return value_; }
    bool is_constant() const override { return true; }

private:
    Color value_;
    int channels_;
};

/// Reads parameter `name` as a volume: a nested <volume> (or a <ref> to one), or a number or
/// colour (rgb/srgb/spectrum), which becomes a ConstantVolume (1 channel when grey). Missing ->
/// a constant `def`. A negative or non-finite value is a located SceneError.
std::shared_ptr<Volume> get_volume(const Properties& props, const std::string& name,
                                   const Color& def);

}  // namespace femto
