// Internal: the scene IR (XML elements with file/line/column) and the passes that run on it
// before instantiation: include expansion, version upgrade, defaults and $param substitution.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "femto/error.h"

namespace femto::detail {

struct XmlAttribute {
    std::string name, value;
};

struct XmlNode {
    std::string tag;
    std::vector<XmlAttribute> attributes;
    std::vector<XmlNode> children;
    SourceLocation location;
    std::string base_dir;  ///< folder of the file this element came from
    std::string root_dir;  ///< folder of the top-level scene file
    /// On the root <scene> only: the <path> folders (Mitsuba 3), the latest first.
    std::vector<std::string> search_dirs;

    const std::string* attribute(const std::string& name) const;
    std::string* attribute(const std::string& name);
};

/// Parses, upgrades and expands a scene file into the IR whose root is <scene>.
/// `defines` are the -D name=value overrides; one the scene does not use (no <default> and no
/// $name of that name) is an error, or a warning when `lenient`.
XmlNode parse_scene_file(const std::string& path,
                         const std::vector<std::pair<std::string, std::string>>& defines,
                         bool lenient = false);
/// Same for XML text; relative paths resolve against `base_dir`.
XmlNode parse_scene_string(const std::string& xml, const std::string& base_dir,
                           const std::vector<std::pair<std::string, std::string>>& defines,
                           bool lenient = false);

/// Where a file name written in `node` was looked up, and what was found.
struct FileSearch {
    std::string path;  ///< the file found, or the candidate next to the naming file
    bool found = false;
    std::vector<std::string> searched;  ///< the folders tried, in order (none when absolute)
};
/// Looks a relative file name up as Mitsuba does: in the <path> folders (`search_dirs`,
/// Mitsuba 3), next to the file that names it, then next to the top-level scene file.
FileSearch find_file(const XmlNode& node, const std::string& name,
                     const std::vector<std::string>& search_dirs);

/// camelCase -> snake_case with Mitsuba's irregular names (intIOR -> int_ior, ...).
std::string upgrade_parameter_name(const std::string& name);
/// Plugin type renamed between Mitsuba 0.x and femto/Mitsuba 3 for a tag, or the same name.
std::string upgrade_plugin_type(const std::string& tag, const std::string& type);

}  // namespace femto::detail
