// Internal: Mitsuba's `shapegroup` and `instance` shapes, built into the host (not plugins):
// the Embree scene traces each group once, as a child scene that every instance places with
// its transform (RTC_GEOMETRY_TYPE_INSTANCE), so memory does not grow with the instances.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "femto/plugin.h"
#include "femto/shape.h"

namespace femto::detail {

/// `<shape type="shapegroup" id="...">`: shapes that are not rendered themselves, only
/// through instances. As in Mitsuba 3, they may not emit, hold a sensor, or be groups or
/// instances themselves.
class ShapeGroup final : public Shape {
public:
    explicit ShapeGroup(const Properties& props);
    const std::vector<std::shared_ptr<Shape>>& shapes() const { return shapes_; }

private:
    std::vector<std::shared_ptr<Shape>> shapes_;
};

/// `<shape type="instance"><ref id="group"/><transform name="to_world">...`: one placement of
/// a shapegroup.
class ShapeInstance final : public Shape {
public:
    explicit ShapeInstance(const Properties& props);
    const ShapeGroup& group() const { return *group_; }
    const Transform& transform() const { return to_world_; }

private:
    std::shared_ptr<ShapeGroup> group_;
};

/// The descriptor of a built-in shape type (`shapegroup`, `instance`), or null.
const PluginDescriptor* builtin_shape(const std::string& type);

/// The media the shape, or any shape an instance places, bounds (interior and exterior; may
/// repeat one).
std::vector<const Medium*> shape_media(const Shape& shape);

}  // namespace femto::detail
