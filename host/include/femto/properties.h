// femto public API: the typed parameter map a plugin is constructed from.
//
// Every entry remembers where it was written and whether the plugin read it. After a plugin's
// constructor returns, the host reports every unread entry as an error (a warning with
// --lenient), so a misspelt or unsupported parameter never passes silently.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "femto/color.h"
#include "femto/error.h"
#include "femto/math.h"
#include "femto/object.h"
#include "femto/transform.h"

namespace femto {

class Properties {
public:
    enum class Type { Bool, Integer, Float, String, Point, Vector, Color, Transform, Object };
    /// Points and vectors share the Vec3 alternative; `type` tells them apart.
    using Value =
        std::variant<bool, int64_t, double, std::string, Vec3, Color, Transform, ObjectPtr>;
    struct Entry {
        std::string name;
        Type type;
        Value value;
        SourceLocation location;
        mutable bool read = false;
    };

    Properties() = default;
    Properties(std::string plugin_type, SourceLocation location)
        : plugin_type_(std::move(plugin_type)), location_(std::move(location)) {}

    /// The `type="..."` of the object being built, and where its tag is.
    const std::string& plugin_type() const { return plugin_type_; }
    const SourceLocation& location() const { return location_; }
    const std::string& id() const { return id_; }
    void set_id(std::string id) { id_ = std::move(id); }

    // -- filled by the scene loader ------------------------------------------------------
    /// Adds or replaces an entry. (The scene loader refuses a name given twice in one object,
    /// as Mitsuba 3 does; replacing is for code that builds Properties itself.)
    void set(const std::string& name, Type type, Value value, SourceLocation loc = {});
    void set_bool(const std::string& n, bool v) { set(n, Type::Bool, v); }
    void set_int(const std::string& n, int64_t v) { set(n, Type::Integer, v); }
    void set_float(const std::string& n, double v) { set(n, Type::Float, v); }
    void set_string(const std::string& n, std::string v) { set(n, Type::String, std::move(v)); }
    void set_color(const std::string& n, const Color& v) { set(n, Type::Color, v); }
    void set_point(const std::string& n, const Vec3& v);
    void set_vector(const std::string& n, const Vec3& v);
    void set_transform(const std::string& n, const Transform& v) { set(n, Type::Transform, v); }
    void set_object(const std::string& n, ObjectPtr v, SourceLocation loc = {}) {
        set(n, Type::Object, std::move(v), std::move(loc));
    }

    // -- read by plugins -------------------------------------------------------------------
    bool has(const std::string& name) const { return find(name) != nullptr; }
    /// Type of an entry (the entry must exist).
    Type type(const std::string& name) const;

    // Getters without a default throw a SceneError when the entry is missing; all throw
    // on a wrong type and mark the entry read. Integers are accepted where floats are asked.
    bool get_bool(const std::string& name) const;
    bool get_bool(const std::string& name, bool def) const;
    int64_t get_int(const std::string& name) const;
    int64_t get_int(const std::string& name, int64_t def) const;
    /// Non-finite values (NaN, inf) are rejected with a located error.
    double get_float(const std::string& name) const;
    double get_float(const std::string& name, double def) const;
    std::string get_string(const std::string& name) const;
    std::string get_string(const std::string& name, const std::string& def) const;
    Vec3 get_point(const std::string& name) const;
    Vec3 get_point(const std::string& name, const Vec3& def) const;
    Vec3 get_vector(const std::string& name) const;
    Vec3 get_vector(const std::string& name, const Vec3& def) const;
    /// A float is accepted as a grey colour.
    Color get_color(const std::string& name) const;
    Color get_color(const std::string& name, const Color& def) const;
    Transform get_transform(const std::string& name) const;
    Transform get_transform(const std::string& name, const Transform& def) const;
    /// A named child object, or nullptr when absent; a SceneError if it has another kind.
    ObjectPtr get_object(const std::string& name, PluginKind kind) const;
    /// All child objects of a kind, named or not, in document order; marks them read.
    std::vector<ObjectPtr> objects(PluginKind kind) const;
    /// The one child object of `kind` (named or not), or nullptr when there is none; a
    /// SceneError "give at most one <tag>", located at the second, when there are several.
    ObjectPtr child(PluginKind kind) const;
    /// As child(kind), but builds plugin `default_type` with default parameters when no child
    /// is given (recorded as the default of the entry named after the kind's tag).
    ObjectPtr child(PluginKind kind, const std::string& default_type) const;

    // -- defaults used ---------------------------------------------------------------------
    /// A default a getter returned for an absent entry: the entry name and the default as
    /// text ("0.5", "1e+30", "true", "(0, 0, 1)" for a non-grey colour or a point,
    /// "identity", a plugin type for a default child).
    struct DefaultUse {
        std::string name;
        std::string value;
    };
    /// Every default used so far, in call order. It exists so that a plugin's schema (the
    /// defaults it documents) can be checked against what its constructor really does
    /// (tests/unit/test_plugin_schemas.cpp).
    const std::vector<DefaultUse>& defaults_used() const { return defaults_used_; }
    /// Records a default used for absent entry `name`; for helpers that read an entry their
    /// own way (get_texture(), read_ior(), ...). The getters above record theirs themselves.
    void note_default(const std::string& name, std::string value) const;

    /// Throws a SceneError located at entry `name` (or at the object when it is absent).
    [[noreturn]] void fail(const std::string& name, const std::string& message) const;
    /// Location of an entry, or of the object itself when the entry does not exist.
    SourceLocation location_of(const std::string& name) const;

    const std::vector<Entry>& entries() const { return entries_; }
    std::vector<const Entry*> unread() const;
    static const char* type_name(Type t);

private:
    const Entry* find(const std::string& name) const;
    const Entry& require(const std::string& name, Type type) const;

    std::string plugin_type_;
    SourceLocation location_;
    std::string id_;
    std::vector<Entry> entries_;
    mutable std::vector<DefaultUse> defaults_used_;
};

}  // namespace femto
