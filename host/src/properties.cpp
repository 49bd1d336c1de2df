#include "femto/properties.h"

#include <fmt/format.h>

#include <cmath>

#include "femto/plugin.h"
#include "femto/texture.h"
#include "femto/volume.h"
#include "util/strings.h"

namespace femto {

namespace {
constexpr struct {
    PluginKind kind;
    const char* tag;
} kKindTags[] = {
    {PluginKind::Integrator, "integrator"},
    {PluginKind::Sensor, "sensor"},
    {PluginKind::Film, "film"},
    {PluginKind::ReconstructionFilter, "rfilter"},
    {PluginKind::TemporalFilter, "tfilter"},
    {PluginKind::Sampler, "sampler"},
    {PluginKind::Shape, "shape"},
    {PluginKind::Bsdf, "bsdf"},
    {PluginKind::Emitter, "emitter"},
    {PluginKind::Texture, "texture"},
    {PluginKind::Medium, "medium"},
    {PluginKind::Phase, "phase"},
    {PluginKind::Volume, "volume"},
    {PluginKind::Distance, "distance"},
    {PluginKind::Connection, "connection"},
    {PluginKind::Angular, "angular"},
};
std::string default_text(bool v) { return v ? "true" : "false"; }
std::string default_text(int64_t v) { return std::to_string(v); }
std::string default_text(double v) { return fmt::format("{}", v); }
std::string default_text(const std::string& v) { return v; }
std::string default_text(const Vec3& v) { return fmt::format("({}, {}, {})", v.x, v.y, v.z); }
std::string default_text(const Color& c) {
    return c.r == c.g && c.g == c.b ? fmt::format("{}", c.r)
                                    : fmt::format("({}, {}, {})", c.r, c.g, c.b);
}
std::string default_text(const Transform& t) {
    return t.is_identity() ? "identity" : "(a transform other than identity)";
}
}  // namespace

const char* kind_tag(PluginKind kind) {
    for (const auto& k : kKindTags)
        if (k.kind == kind) return k.tag;
    return "?";
}

bool kind_from_tag(const std::string& tag, PluginKind& kind) {
    for (const auto& k : kKindTags)
        if (tag == k.tag) {
            kind = k.kind;
            return true;
        }
    return false;
}

const char* Properties::type_name(Type t) {
    switch (t) {
        case Type::Bool:
            return "boolean";
        case Type::Integer:
            return "integer";
        case Type::Float:
            return "float";
        case Type::String:
            return "string";
        case Type::Point:
            return "point";
        case Type::Vector:
            return "vector";
        case Type::Color:
            return "color";
        case Type::Transform:
            return "transform";
        case Type::Object:
            return "object";
    }
    return "?";
}

void Properties::set(const std::string& name, Type type, Value value, SourceLocation loc) {
    for (auto& e : entries_)
        if (e.name == name) {
            e.type = type;
            e.value = std::move(value);
            e.location = std::move(loc);
            e.read = false;
            return;
        }
    entries_.push_back(Entry{name, type, std::move(value), std::move(loc), false});
}

void Properties::set_point(const std::string& n, const Vec3& v) { set(n, Type::Point, v); }
void Properties::set_vector(const std::string& n, const Vec3& v) { set(n, Type::Vector, v); }

const Properties::Entry* Properties::find(const std::string& name) const {
    for (const auto& e : entries_)
        if (e.name == name) return &e;
    return nullptr;
}

Properties::Type Properties::type(const std::string& name) const {
    const Entry* e = find(name);
    if (!e) fail(name, "parameter \"" + name + "\" is missing");
    return e->type;
}

SourceLocation Properties::location_of(const std::string& name) const {
    const Entry* e = find(name);
    return e && !e->location.file.empty() ? e->location : location_;
}

void Properties::fail(const std::string& name, const std::string& message) const {
    std::string where = plugin_type_.empty() ? std::string() : "\"" + plugin_type_ + "\": ";
    throw SceneError(location_of(name), where + message);
}

const Properties::Entry& Properties::require(const std::string& name, Type type) const {
    const Entry* e = find(name);
    if (!e) fail(name, "required parameter \"" + name + "\" (" + type_name(type) + ") is missing");
    const bool ok = e->type == type || (type == Type::Float && e->type == Type::Integer) ||
                    (type == Type::Color && (e->type == Type::Float || e->type == Type::Integer)) ||
                    (type == Type::Point && e->type == Type::Vector) ||
                    (type == Type::Vector && e->type == Type::Point);
    if (!ok)
        fail(name, "parameter \"" + name + "\" must be " + detail::with_article(type_name(type)) +
                       ", but " + detail::with_article(type_name(e->type)) + " was given");
    e->read = true;
    return *e;
}

bool Properties::get_bool(const std::string& name) const {
    return std::get<bool>(require(name, Type::Bool).value);
}
bool Properties::get_bool(const std::string& name, bool def) const {
    if (has(name)) return get_bool(name);
    note_default(name, default_text(def));
    return def;
}
int64_t Properties::get_int(const std::string& name) const {
    return std::get<int64_t>(require(name, Type::Integer).value);
}
int64_t Properties::get_int(const std::string& name, int64_t def) const {
    if (has(name)) return get_int(name);
    note_default(name, default_text(def));
    return def;
}
double Properties::get_float(const std::string& name) const {
    const Entry& e = require(name, Type::Float);
    const double v = e.type == Type::Integer ? static_cast<double>(std::get<int64_t>(e.value))
                                             : std::get<double>(e.value);
    if (!std::isfinite(v)) fail(name, "parameter \"" + name + "\" must be a finite number");
    return v;
}
double Properties::get_float(const std::string& name, double def) const {
    if (has(name)) return get_float(name);
    note_default(name, default_text(def));
    return def;
}
std::string Properties::get_string(const std::string& name) const {
    return std::get<std::string>(require(name, Type::String).value);
}
std::string Properties::get_string(const std::string& name, const std::string& def) const {
    if (has(name)) return get_string(name);
    note_default(name, default_text(def));
    return def;
}
Vec3 Properties::get_point(const std::string& name) const {
    return std::get<Vec3>(require(name, Type::Point).value);
}
Vec3 Properties::get_point(const std::string& name, const Vec3& def) const {
    if (has(name)) return get_point(name);
    note_default(name, default_text(def));
    return def;
}
Vec3 Properties::get_vector(const std::string& name) const {
    return std::get<Vec3>(require(name, Type::Vector).value);
}
Vec3 Properties::get_vector(const std::string& name, const Vec3& def) const {
    if (has(name)) return get_vector(name);
    note_default(name, default_text(def));
    return def;
}
Color Properties::get_color(const std::string& name) const {
    const Entry& e = require(name, Type::Color);
    if (e.type == Type::Color) {
        const Color c = std::get<Color>(e.value);
        if (!c.is_finite()) fail(name, "colour \"" + name + "\" must be finite");
        return c;
    }
    return Color(static_cast<float>(get_float(name)));
}
Color Properties::get_color(const std::string& name, const Color& def) const {
    if (has(name)) return get_color(name);
    note_default(name, default_text(def));
    return def;
}
Transform Properties::get_transform(const std::string& name) const {
    return std::get<Transform>(require(name, Type::Transform).value);
}
Transform Properties::get_transform(const std::string& name, const Transform& def) const {
    if (has(name)) return get_transform(name);
    note_default(name, default_text(def));
    return def;
}

ObjectPtr Properties::get_object(const std::string& name, PluginKind kind) const {
    const Entry* e = find(name);
    if (!e) return nullptr;
    const ObjectPtr& obj = std::get<ObjectPtr>(require(name, Type::Object).value);
    if (obj->kind() != kind)
        fail(name, "\"" + name + "\" must be " + detail::tag_with_article(kind) + ", but " +
                       detail::tag_with_article(obj->kind()) + " was given");
    return obj;
}

std::vector<ObjectPtr> Properties::objects(PluginKind kind) const {
    std::vector<ObjectPtr> out;
    for (const auto& e : entries_)
        if (e.type == Type::Object) {
            const ObjectPtr& obj = std::get<ObjectPtr>(e.value);
            if (obj && obj->kind() == kind) {
                e.read = true;
                out.push_back(obj);
            }
        }
    return out;
}

ObjectPtr Properties::child(PluginKind kind) const {
    const Entry* first = nullptr;
    for (const auto& e : entries_)
        if (e.type == Type::Object) {
            const ObjectPtr& obj = std::get<ObjectPtr>(e.value);
            if (!obj || obj->kind() != kind) continue;
            e.read = true;
            if (first) {
                const std::string where =
                    plugin_type_.empty() ? std::string() : "\"" + plugin_type_ + "\": ";
                throw SceneError(e.location.file.empty() ? location_ : e.location,
                                 where + "give at most one <" + kind_tag(kind) + ">");
            }
            first = &e;
        }
    return first ? std::get<ObjectPtr>(first->value) : nullptr;
}

ObjectPtr Properties::child(PluginKind kind, const std::string& default_type) const {
    if (ObjectPtr obj = child(kind)) return obj;
    note_default(kind_tag(kind), default_type);
    return create_default_object(kind, default_type, location_);
}

void Properties::note_default(const std::string& name, std::string value) const {
    defaults_used_.push_back(DefaultUse{name, std::move(value)});
}

std::vector<const Properties::Entry*> Properties::unread() const {
    std::vector<const Entry*> out;
    for (const auto& e : entries_)
        if (!e.read) out.push_back(&e);
    return out;
}

std::shared_ptr<Texture> get_texture(const Properties& props, const std::string& name,
                                     const Color& def) {
    if (!props.has(name)) {
        props.note_default(name, default_text(def));
        return std::make_shared<ConstantTexture>(def);
    }
    if (props.type(name) == Properties::Type::Object) {
        auto obj = props.get_object(name, PluginKind::Texture);
        return std::static_pointer_cast<Texture>(obj);
    }
    const Color c = props.get_color(name);
    if (c.r < 0 || c.g < 0 || c.b < 0)
        props.fail(name, fmt::format("\"{}\" must not be negative, got {}: a reflectance below 0 "
                                     "would make negative radiance",
                                     name, default_text(c)));
    return std::make_shared<ConstantTexture>(c);
}

std::shared_ptr<Volume> get_volume(const Properties& props, const std::string& name,
                                   const Color& def) {
    // A grey value is a scalar (1 channel): what a density or a scalar sigma_t must be.
    const auto constant = [](const Color& c) {
        return std::make_shared<ConstantVolume>(c, c.r == c.g && c.g == c.b ? 1 : 3);
    };
    if (!props.has(name)) {
        props.note_default(name, default_text(def));
        return constant(def);
    }
    if (props.type(name) == Properties::Type::Object)
        return std::static_pointer_cast<Volume>(props.get_object(name, PluginKind::Volume));
    const Color c = props.get_color(name);
    if (!(c.r >= 0 && c.g >= 0 && c.b >= 0))
        props.fail(name, fmt::format("\"{}\" must not be negative, got {}", name, default_text(c)));
    return constant(c);
}

}  // namespace femto
