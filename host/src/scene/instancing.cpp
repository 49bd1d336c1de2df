// Mitsuba's `shapegroup` and `instance` (see instancing.h).
#include "scene/instancing.h"

#include <fmt/format.h>

#include "femto/error.h"

namespace femto::detail {

namespace {

bool is_group_or_instance(const Shape& s) {
    return dynamic_cast<const ShapeGroup*>(&s) || dynamic_cast<const ShapeInstance*>(&s);
}

// The nested objects (given as <shape>, or as <ref>: both arrive as positional entries).
std::vector<std::pair<ObjectPtr, SourceLocation>> nested_objects(const Properties& props) {
    std::vector<std::pair<ObjectPtr, SourceLocation>> out;
    for (const Properties::Entry& e : props.entries())
        if (e.type == Properties::Type::Object) {
            e.read = true;
            out.emplace_back(std::get<ObjectPtr>(e.value), e.location);
        }
    return out;
}

}  // namespace

ShapeGroup::ShapeGroup(const Properties& props) : Shape(props) {
    for (auto& [obj, where] : nested_objects(props)) {
        if (!obj || obj->kind() != PluginKind::Shape)
            throw SceneError(where, fmt::format("a shapegroup holds only shapes, not a <{}>",
                                                obj ? kind_tag(obj->kind()) : "?"));
        auto shape = std::static_pointer_cast<Shape>(obj);
        if (is_group_or_instance(*shape))
            throw SceneError(where,
                             "nested instancing is not permitted: a shapegroup cannot "
                             "hold a shapegroup or an instance (as in Mitsuba 3)");
        if (shape->emitter())
            throw SceneError(where,
                             "instancing of emitters is not supported: a shape in a "
                             "shapegroup cannot hold an <emitter> (as in Mitsuba 3); "
                             "write the emitting shape outside the group");
        if (shape->sensor_ptr())
            throw SceneError(where,
                             "instancing of sensors is not supported: a shape in a "
                             "shapegroup cannot hold a <sensor> (as in Mitsuba 3)");
        shapes_.push_back(std::move(shape));
    }
    if (shapes_.empty()) throw SceneError(props.location(), "the shapegroup holds no shapes");
}

ShapeInstance::ShapeInstance(const Properties& props) : Shape(props) {
    const auto& m = to_world_.matrix();
    if (m[3][0] != 0 || m[3][1] != 0 || m[3][2] != 0 || m[3][3] != 1)
        props.fail("to_world", "an instance's to_world must be affine (no projective part)");
    const auto nested = nested_objects(props);
    if (nested.size() != 1)
        throw SceneError(props.location(),
                         fmt::format("an instance needs exactly one <ref id=\"...\"/> to a "
                                     "shapegroup, but {} objects were given",
                                     nested.size()));
    const auto& [obj, where] = nested[0];
    group_ = std::dynamic_pointer_cast<ShapeGroup>(obj);
    if (!group_) {
        if (obj && dynamic_cast<const ShapeInstance*>(obj.get()))
            throw SceneError(where,
                             "nested instancing is not permitted: an instance must "
                             "refer to a shapegroup, not to another instance");
        throw SceneError(where, fmt::format("an instance must refer to a <shape "
                                            "type=\"shapegroup\">, not to a <{}{}>",
                                            obj ? kind_tag(obj->kind()) : "?",
                                            obj ? " type=\"" + obj->type_name() + "\"" : ""));
    }
}

namespace {

template <typename T>
Object* make(const Properties& props) {
    return new T(props);
}

}  // namespace

const PluginDescriptor* builtin_shape(const std::string& type) {
    static const PluginDescriptor group{
        kPluginAbiVersion,
        PluginKind::Shape,
        "shapegroup",
        "Shapes that are rendered only where instances place them (Mitsuba's shapegroup)",
        {},
        make<ShapeGroup>};
    static const PluginDescriptor instance{
        kPluginAbiVersion,
        PluginKind::Shape,
        "instance",
        "A shapegroup placed by to_world (Mitsuba's instance)",
        {{"to_world", "transform", "identity", "where the group is placed"}},
        make<ShapeInstance>};
    if (type == "shapegroup") return &group;
    if (type == "instance") return &instance;
    return nullptr;
}

std::vector<const Medium*> shape_media(const Shape& shape) {
    std::vector<const Medium*> media;
    const auto add = [&](const Shape& s) {
        for (const Medium* m : {s.interior(), s.exterior()})
            if (m) media.push_back(m);
    };
    add(shape);
    if (const auto* inst = dynamic_cast<const ShapeInstance*>(&shape))
        for (const auto& s : inst->group().shapes()) add(*s);
    return media;
}

}  // namespace femto::detail
