// femto public API: the base of every scene object a plugin creates.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "femto/error.h"

namespace femto {

/// The kinds of plugin. The XML tag decides which kind a scene object must have.
enum class PluginKind {
    Integrator,
    Sensor,
    Film,
    ReconstructionFilter,  // <rfilter>
    TemporalFilter,        // <tfilter>
    Sampler,
    Shape,
    Bsdf,
    Emitter,
    Texture,
    Medium,
    Phase,
    Volume,
    Distance,    // <distance>: time-sampling strategies (transient media)
    Connection,  // <connection>
    Angular,     // <angular>
};

/// XML tag of a kind ("bsdf", "rfilter", ...).
const char* kind_tag(PluginKind kind);
/// Inverse of kind_tag(); returns false for an unknown tag.
bool kind_from_tag(const std::string& tag, PluginKind& kind);

/// One documented parameter of a plugin schema. `type` is free text for the docs ("float",
/// "color|texture", "transform", "bsdf" for a child object, ...), alternatives separated by
/// '|'. The alternative "filename" declares a file the plugin reads: the loader looks a
/// relative <string> value up next to the scene file that names it (and in the scene's <path>
/// folders) and hands the plugin the path found, or reports a file found nowhere. A name "*"
/// in the schema accepts any entry (for plugins that forward parameters).
struct ParamSpec {
    const char* name;
    const char* type;
    const char* default_value;  ///< "" when required / none
    const char* doc;
    /// The base class whose constructor reads the parameter ("Film", "Shape", ...), or
    /// nullptr for the plugin's own parameters. Set by inherit_params().
    const char* inherited_from = nullptr;
};

/// `base` followed by `own`, each of `own` tagged as declared by `owner`: how a base class
/// extends its base's inherited_params() with what its own constructor reads.
inline std::vector<ParamSpec> inherit_params(std::vector<ParamSpec> base, const char* owner,
                                             std::vector<ParamSpec> own) {
    for (ParamSpec& p : own) {
        p.inherited_from = owner;
        base.push_back(p);
    }
    return base;
}

/// A plugin's schema: `inherited` (its base classes' parameters, in their order) with each
/// entry of `own` that has the same name put in its place (so a plugin can change a default
/// or a description), then the rest of `own` in order. FEMTO_PLUGIN calls this.
inline std::vector<ParamSpec> merge_params(std::vector<ParamSpec> inherited,
                                           const std::vector<ParamSpec>& own) {
    std::vector<ParamSpec> rest;
    for (const ParamSpec& p : own) {
        bool replaced = false;
        for (ParamSpec& q : inherited)
            if (std::string(q.name) == p.name) {
                q = p;
                replaced = true;
            }
        if (!replaced) rest.push_back(p);
    }
    inherited.insert(inherited.end(), rest.begin(), rest.end());
    return inherited;
}

class Object {
public:
    virtual ~Object() = default;
    /// The parameters this class's constructor reads, for the plugin schemas. Every base class
    /// whose constructor reads Properties hides this with its base's list plus its own reads
    /// (see inherit_params()), defined next to that constructor; FEMTO_PLUGIN puts
    /// `CLASS::inherited_params()` before the plugin's own list.
    static std::vector<ParamSpec> inherited_params() { return {}; }
    virtual PluginKind kind() const = 0;
    /// The id given in the scene (`id="..."`), or empty.
    const std::string& id() const { return id_; }
    void set_id(std::string id) { id_ = std::move(id); }
    /// The plugin type it was built from (`type="..."`); set by the host.
    const std::string& type_name() const { return type_name_; }
    void set_type_name(std::string t) { type_name_ = std::move(t); }
    /// Where the object's tag is in the scene (empty for objects not built from a file); set
    /// by the host, for errors found after construction (preprocess(), prepare()).
    const SourceLocation& location() const { return location_; }
    void set_location(SourceLocation location) { location_ = std::move(location); }

private:
    std::string id_, type_name_;
    SourceLocation location_;
};

using ObjectPtr = std::shared_ptr<Object>;

}  // namespace femto
