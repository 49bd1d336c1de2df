// Internal: instantiation of the scene IR into plugin objects.
#pragma once

#include <string>

#include "femto/error.h"
#include "femto/host.h"
#include "femto/object.h"
#include "femto/properties.h"

namespace femto::detail {

/// Builds a plugin with no parameters (the defaults a parent object supplies, e.g. a sensor's
/// hdrfilm). Uses the plugin folders of the load in progress.
ObjectPtr create_default(PluginKind kind, const std::string& type, const SourceLocation& loc);
/// Builds a plugin from `props`, checked against its schema and for unread entries as the
/// loader checks a scene's objects. Uses the plugin folders of the load in progress.
ObjectPtr create_with(PluginKind kind, const std::string& type, const Properties& props);

}  // namespace femto::detail
