// Internal: instantiation of the scene IR into plugin objects.
#pragma once

#include <string>

#include "femto/error.h"
#include "femto/host.h"
#include "femto/object.h"

namespace femto::detail {

/// Builds a plugin with no parameters (the defaults a parent object supplies, e.g. a sensor's
/// hdrfilm). Uses the plugin folders of the load in progress.
ObjectPtr create_default(PluginKind kind, const std::string& type, const SourceLocation& loc);

}  // namespace femto::detail
