// femto public API: how a shared library declares the plugin it contains.
//
// A plugin library exports exactly one C symbol, `femto_plugin_descriptor`, returning a
// PluginDescriptor. Use FEMTO_PLUGIN below rather than writing it by hand:
//
//     class AmbientOcclusion : public femto::Integrator { ... };
//     FEMTO_PLUGIN(AmbientOcclusion, femto::PluginKind::Integrator, "ao",
//                  "Ambient occlusion (fraction of unoccluded hemisphere)",
//                  {{"samples", "integer", "16", "occlusion rays per camera sample"}})
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "femto/object.h"
#include "femto/properties.h"

namespace femto {

/// Bumped whenever a public header changes in a way that breaks compiled plugins.
inline constexpr uint32_t kPluginAbiVersion = 5;

/// One documented parameter. `type` is free text for the docs ("float", "color|texture",
/// "transform", "bsdf" for a child object, ...). A name "*" in the schema accepts any entry
/// (for plugins that forward parameters).
struct ParamSpec {
    const char* name;
    const char* type;
    const char* default_value;  ///< "" when required / none
    const char* doc;
};

struct PluginDescriptor {
    uint32_t abi_version;
    PluginKind kind;
    const char* type_name;
    const char* description;
    std::vector<ParamSpec> params;
    /// Builds the object; throws SceneError on bad parameters.
    Object* (*create)(const Properties& props);
};

/// Builds plugin `type` of `kind` with default parameters, for a parent object whose child
/// was not given in the scene (e.g. a film's default <tfilter>). Throws SceneError.
ObjectPtr create_default_object(PluginKind kind, const std::string& type,
                                const SourceLocation& loc);

}  // namespace femto

extern "C" {
typedef const femto::PluginDescriptor* (*femto_plugin_descriptor_fn)();
}

#define FEMTO_PLUGIN(CLASS, KIND, TYPE_NAME, DESCRIPTION, ...)                                  \
    extern "C" __attribute__((visibility("default"))) const femto::PluginDescriptor*            \
    femto_plugin_descriptor() {                                                                 \
        static const femto::PluginDescriptor descriptor{                                        \
            femto::kPluginAbiVersion,                                                           \
            KIND,                                                                               \
            TYPE_NAME,                                                                          \
            DESCRIPTION,                                                                        \
            std::vector<femto::ParamSpec>                                                       \
                __VA_ARGS__,                                                                    \
            [](const femto::Properties& props) -> femto::Object* { return new CLASS(props); }}; \
        return &descriptor;                                                                     \
    }
