// Internal: finds, opens and caches plugin libraries (lazily, one per scene type used).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "femto/error.h"
#include "femto/plugin.h"

namespace femto::detail {

/// Folders searched, in order: `extra_dirs` (--plugin-dir, each of which must be a folder:
/// SceneError otherwise), the build's plugin folder, the install folder next to libfemto, then
/// $FEMTO_PLUGIN_PATH (colon-separated). The first library of a type wins.
std::vector<std::string> plugin_search_path(const std::vector<std::string>& extra_dirs);

/// The descriptor of `type`, which must be of `kind`; throws SceneError at `loc` otherwise.
const PluginDescriptor& find_plugin(PluginKind kind, const std::string& type,
                                    const std::vector<std::string>& extra_dirs,
                                    const SourceLocation& loc);

/// Opens every plugin library on the search path.
std::vector<std::pair<std::string, const PluginDescriptor*>> list_plugins(
    const std::vector<std::string>& extra_dirs);

std::vector<std::string> loaded_plugin_files();

}  // namespace femto::detail
