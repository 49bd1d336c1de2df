// femto public API: the base of every scene object a plugin creates.
#pragma once

#include <memory>
#include <string>

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

class Object {
public:
    virtual ~Object() = default;
    virtual PluginKind kind() const = 0;
    /// The id given in the scene (`id="..."`), or empty.
    const std::string& id() const { return id_; }
    void set_id(std::string id) { id_ = std::move(id); }
    /// The plugin type it was built from (`type="..."`); set by the host.
    const std::string& type_name() const { return type_name_; }
    void set_type_name(std::string t) { type_name_ = std::move(t); }

private:
    std::string id_, type_name_;
};

using ObjectPtr = std::shared_ptr<Object>;

}  // namespace femto
