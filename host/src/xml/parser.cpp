#include "xml/parser.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <pugixml.hpp>
#include <set>
#include <sstream>

#include "femto/input_file.h"
#include "util/files.h"
#include "util/lenient.h"
#include "util/line_table.h"
#include "util/strings.h"

namespace fs = std::filesystem;

namespace femto::detail {

const std::string* XmlNode::attribute(const std::string& name) const {
    for (const auto& a : attributes)
        if (a.name == name) return &a.value;
    return nullptr;
}
std::string* XmlNode::attribute(const std::string& name) {
    for (auto& a : attributes)
        if (a.name == name) return &a.value;
    return nullptr;
}

namespace {

constexpr int kMaxIncludeDepth = 32;
// Deeper nesting than any real scene needs; the passes and the instantiation recurse once per
// level, so a bound keeps a hostile file from overflowing the stack. Includes count too.
constexpr int kMaxElementDepth = 100;
constexpr size_t kMaxSceneFileBytes = size_t(1) << 30;

// Version differences are data: names that the generic camelCase -> snake_case rule gets wrong,
// and plugin types that were renamed.
const std::map<std::string, std::string> kIrregularNames = {
    {"intIOR", "int_ior"},          {"extIOR", "ext_ior"},   {"toUV", "to_uv"},
    {"fovAxis", "fov_axis"},        {"rrDepth", "rr_depth"}, {"uvScale", "uv_scale"},
    {"densityMultiplier", "scale"},  // media: 0.x's densityMultiplier is Mitsuba 3's scale
};
struct TypeRename {
    const char* tag;
    const char* old_type;
    const char* new_type;
};
constexpr TypeRename kTypeRenames[] = {
    {"sampler", "sobol", "ldsampler"},
};
// Parameters a 0.x file implies where Mitsuba 3 changed what an object means without changing
// its name: added to the object in 0.x files unless the file gives them.
struct ImpliedParameter {
    const char* tag;
    const char* type;
    const char* property_tag;
    const char* name;
    const char* value;
};
constexpr ImpliedParameter kImpliedParameters[] = {
    // 0.6's gridvolume spans the box stored in the file with its first and last data points on
    // the box's faces; Mitsuba 3's fills the unit cube with cells whose centres hold the data.
    {"volume", "gridvolume", "boolean", "use_grid_bbox", "true"},
    {"volume", "gridvolume", "string", "lattice", "vertex"},
};

std::string read_file(const std::string& path, const SourceLocation& from) {
    const std::string problem = input_file_problem(path);
    if (!problem.empty())
        throw SceneError(from, fmt::format("scene file \"{}\" does not exist or is not a file "
                                           "({})",
                                           path, problem));
    InputFile file(path, from);
    if (file.size() > kMaxSceneFileBytes)
        throw SceneError(from, fmt::format("scene file \"{}\" is larger than 1 GiB", path));
    return file.read_rest();
}

bool is_blank(const std::string& text) {
    return std::all_of(text.begin(), text.end(), [](unsigned char c) { return std::isspace(c); });
}

// `depth` is the nesting level of `node` (1 for the root of the top-level file).
XmlNode convert(const pugi::xml_node& node, const LineTable& lines, const std::string& file,
                const std::string& base_dir, int depth) {
    XmlNode out;
    out.tag = node.name();
    out.location = lines.at(file, node.offset_debug() - 1);  // column of '<', not of the name
    out.base_dir = base_dir;
    if (depth > kMaxElementDepth)
        throw SceneError(out.location, fmt::format("elements are nested more than {} levels deep",
                                                   kMaxElementDepth));
    for (const auto& a : node.attributes()) {
        if (out.attribute(a.name()))
            throw SceneError(out.location, fmt::format("attribute \"{}\" given twice", a.name()));
        out.attributes.push_back({a.name(), a.value()});
    }
    for (const auto& child : node.children()) {
        if (child.type() == pugi::node_element) {
            out.children.push_back(convert(child, lines, file, base_dir, depth + 1));
        } else if (child.type() == pugi::node_pcdata || child.type() == pugi::node_cdata) {
            if (!is_blank(child.value()))
                throw SceneError(lines.at(file, child.offset_debug()),
                                 fmt::format("unexpected text inside <{}>", out.tag));
        }
    }
    return out;
}

// Returns {major, minor} of a "x.y.z" version string, or throws.
std::pair<int, int> parse_version(const XmlNode& scene) {
    const std::string* v = scene.attribute("version");
    if (!v)
        throw SceneError(scene.location,
                         "<scene> needs a version attribute, e.g. version=\"3.0.0\" "
                         "(femto reads Mitsuba 0.5/0.6 and 3.x files)");
    int major = -1, minor = -1, patch = -1;
    char tail = 0;
    if (std::sscanf(v->c_str(), "%d.%d.%d%c", &major, &minor, &patch, &tail) != 3 || major < 0 ||
        minor < 0 || patch < 0)
        throw SceneError(scene.location, fmt::format("invalid scene version \"{}\" (expected "
                                                     "major.minor.patch)",
                                                     *v));
    if (major > 3)
        throw SceneError(scene.location, fmt::format("scene version {} is newer than femto "
                                                     "understands (0.x and 3.x)",
                                                     *v));
    return {major, minor};
}

void add_implied_parameters(XmlNode& node) {
    const std::string* type = node.attribute("type");
    if (!type) return;
    for (const auto& p : kImpliedParameters) {
        if (node.tag != p.tag || *type != p.type) continue;
        bool given = false;
        for (const auto& c : node.children) {
            const std::string* name = c.attribute("name");
            given = given || (name && *name == p.name);
        }
        if (given) continue;
        XmlNode implied;
        implied.tag = p.property_tag;
        implied.attributes = {{"name", p.name}, {"value", p.value}};
        implied.location = node.location;
        implied.base_dir = node.base_dir;
        node.children.push_back(std::move(implied));
    }
}

// A <default> keeps its name: it names a $parameter and a -D, not a plugin parameter, and
// `$maxDepth` in the same file must still find it (Mitsuba 3 skips defaults too). The 0.x
// transform operation <lookAt> is <lookat>.
void upgrade_tree(XmlNode& node) {
    if (node.tag == "lookAt") node.tag = "lookat";
    if (node.tag != "default")
        if (std::string* name = node.attribute("name")) *name = upgrade_parameter_name(*name);
    if (std::string* type = node.attribute("type")) *type = upgrade_plugin_type(node.tag, *type);
    for (auto& c : node.children) upgrade_tree(c);
    add_implied_parameters(node);
}

void set_root_dir(XmlNode& node, const std::string& root) {
    node.root_dir = root;
    for (auto& c : node.children) set_root_dir(c, root);
}

// Everything in the document besides its root element must be markup that carries nothing
// (declaration, comments, processing instructions): Mitsuba reads one <scene> per file.
void check_nothing_beside_root(const pugi::xml_document& doc, const pugi::xml_node& root,
                               const LineTable& lines, const std::string& file) {
    for (const auto& node : doc.children()) {
        if (node == root) continue;
        if (node.type() == pugi::node_element)
            throw SceneError(lines.at(file, node.offset_debug() - 1),
                             fmt::format("<{}> outside the root element <{}>: a scene file holds "
                                         "one root element; move it inside",
                                         node.name(), root.name()));
        if ((node.type() == pugi::node_pcdata || node.type() == pugi::node_cdata) &&
            !is_blank(node.value())) {
            const std::string text = node.value();
            const size_t first = text.find_first_not_of(" \t\r\n");
            throw SceneError(lines.at(file, node.offset_debug() + ptrdiff_t(first)),
                             fmt::format("text outside the root element <{}>", root.name()));
        }
    }
}

/// `root_depth` is the nesting level the file's root element takes (an included file's root
/// stands in for its <include>).
XmlNode parse_text(const std::string& text, const std::string& file, const std::string& base_dir,
                   const SourceLocation& from, int root_depth) {
    pugi::xml_document doc;
    const pugi::xml_parse_result result =
        doc.load_buffer(text.data(), text.size(),
                        pugi::parse_default | pugi::parse_ws_pcdata_single | pugi::parse_fragment);
    const LineTable lines(text);
    if (!result)
        throw SceneError(lines.at(file, result.offset),
                         fmt::format("malformed XML: {}", result.description()));
    pugi::xml_node root = doc.document_element();
    if (!root)
        throw SceneError(from.file.empty() ? SourceLocation{file, 1, 1} : from,
                         "the file holds no XML element");
    check_nothing_beside_root(doc, root, lines, file);
    XmlNode scene = convert(root, lines, file, base_dir, root_depth);
    if (scene.tag != "scene")
        throw SceneError(scene.location,
                         fmt::format("the root element must be <scene>, not <{}>", scene.tag));
    if (parse_version(scene).first < 2) upgrade_tree(scene);
    return scene;
}

bool is_identifier_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool is_identifier_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// Replaces every $name in the attributes of `node` (not its children) and adds the names to
// `scene_params`. `where` completes the message for an undefined name.
void substitute_attributes(XmlNode& node, const std::map<std::string, std::string>& params,
                           std::set<std::string>& scene_params, const char* where = "") {
    for (auto& a : node.attributes) {
        if (a.value.find('$') == std::string::npos) continue;
        std::string out;
        for (size_t i = 0; i < a.value.size(); ++i) {
            if (a.value[i] != '$' || i + 1 >= a.value.size() ||
                !is_identifier_start(a.value[i + 1])) {
                out += a.value[i];
                continue;
            }
            size_t j = i + 1;
            while (j < a.value.size() && is_identifier_char(a.value[j])) ++j;
            const std::string name = a.value.substr(i + 1, j - i - 1);
            auto it = params.find(name);
            if (it == params.end())
                throw SceneError(
                    node.location,
                    fmt::format("parameter ${} is not defined: add <default name=\"{}\" "
                                "value=\"...\"/>{} or pass -D {}=...",
                                name, name, where, name));
            out += it->second;
            scene_params.insert(name);
            i = j - 1;
        }
        a.value = std::move(out);
    }
}

void substitute(XmlNode& node, const std::map<std::string, std::string>& params,
                std::set<std::string>& scene_params) {
    substitute_attributes(node, params, scene_params);
    for (auto& c : node.children) substitute(c, params, scene_params);
}

// State of the expansion pass, which visits the elements in document order as Mitsuba does:
// a <default> or <path> counts for the <include>s after it.
struct Expansion {
    std::vector<std::string> include_stack;  // canonical paths of the files being read
    const std::map<std::string, std::string>& defines;
    std::map<std::string, std::string> params;  // -D values, then <default>s seen so far
    std::set<std::string>& scene_params;
    std::vector<std::string> search_dirs;  // <path> folders, the latest first
};

// Records a <default> (a -D or an earlier <default> of the same name wins).
void add_default(const XmlNode& c, Expansion& ex) {
    const std::string* name = c.attribute("name");
    const std::string* value = c.attribute("value");
    if (!name || !value || c.attributes.size() != 2 || !c.children.empty())
        throw SceneError(c.location, "<default> takes exactly the attributes name and value");
    if (name->empty() || !is_identifier_start((*name)[0]) ||
        !std::all_of(name->begin(), name->end(), is_identifier_char))
        throw SceneError(c.location, fmt::format("invalid parameter name \"{}\"", *name));
    if (!ex.defines.count(*name) && !ex.params.count(*name)) ex.params[*name] = *value;
    ex.scene_params.insert(*name);
}

// <path value="dir"/> (Mitsuba 3): a folder where the files named later are looked up, before
// the scene's own folders. A relative folder is taken next to the file that names it, else
// looked up as any file is.
void add_search_dir(XmlNode& c, Expansion& ex, bool scene_root) {
    if (!scene_root) throw SceneError(c.location, "<path> can only be a child of <scene>");
    substitute_attributes(c, ex.params, ex.scene_params, " before this <path>");
    const std::string* value = c.attribute("value");
    if (!value || c.attributes.size() != 1 || !c.children.empty())
        throw SceneError(c.location, "<path> takes exactly one attribute, value");
    if (value->empty()) throw SceneError(c.location, "<path> has an empty value");
    std::vector<std::string> first_here{c.base_dir};
    first_here.insert(first_here.end(), ex.search_dirs.begin(), ex.search_dirs.end());
    const FileSearch found = find_file(c, *value, first_here);
    std::error_code ec;
    if (!found.found)
        throw SceneError(c.location, fmt::format("<path>: folder \"{}\" not found (searched: {})",
                                                 *value, join(found.searched)));
    if (!fs::is_directory(found.path, ec))
        throw SceneError(c.location, fmt::format("<path>: \"{}\" is not a folder", found.path));
    fs::path dir(found.path);
    if (!dir.has_filename()) dir = dir.parent_path();  // "meshes/" -> "meshes"
    auto& dirs = ex.search_dirs;
    dirs.erase(std::remove(dirs.begin(), dirs.end(), dir.string()), dirs.end());
    dirs.insert(dirs.begin(), dir.string());
}

void expand(XmlNode& node, Expansion& ex, int depth, bool scene_root);

// Reads the file an <include> names and returns its root, expanded.
XmlNode read_include(XmlNode& inc, Expansion& ex, int depth) {
    substitute_attributes(inc, ex.params, ex.scene_params, " before this <include>");
    const std::string* filename = inc.attribute("filename");
    if (!filename || inc.attributes.size() != 1 || !inc.children.empty())
        throw SceneError(inc.location, "<include> takes exactly one attribute, filename");
    const FileSearch found = find_file(inc, *filename, ex.search_dirs);
    if (!found.found && !found.searched.empty())
        throw SceneError(inc.location, fmt::format("included file \"{}\" not found (searched: {})",
                                                   *filename, join(found.searched)));
    const fs::path p = found.path;
    std::error_code ec;
    const fs::path canon = fs::weakly_canonical(p, ec);
    const std::string key = ec ? p.string() : canon.string();
    auto& stack = ex.include_stack;
    if (std::find(stack.begin(), stack.end(), key) != stack.end())
        throw SceneError(inc.location,
                         fmt::format("\"{}\" includes itself (include cycle)", *filename));
    if (stack.size() >= size_t(kMaxIncludeDepth))
        throw SceneError(inc.location, "includes are nested too deeply (more than 32 levels)");
    const std::string text = read_file(p.string(), inc.location);
    XmlNode included = parse_text(text, p.string(), p.parent_path().string(), inc.location, depth);
    set_root_dir(included, inc.root_dir);
    stack.push_back(key);
    expand(included, ex, depth, true);
    stack.pop_back();
    return included;
}

// Moves the <default>s into the parameters, the <path>s into the search folders and replaces
// each <include> by the children of the file's root. `depth` is the nesting level of `node`;
// `scene_root`: `node` is the <scene> of a file.
void expand(XmlNode& node, Expansion& ex, int depth, bool scene_root) {
    std::vector<XmlNode> out;
    out.reserve(node.children.size());
    for (auto& child : node.children) {
        if (child.tag == "default") {
            add_default(child, ex);
        } else if (child.tag == "path") {
            add_search_dir(child, ex, scene_root);
        } else if (child.tag == "include") {
            XmlNode included = read_include(child, ex, depth);
            for (auto& c : included.children) out.push_back(std::move(c));
        } else {
            expand(child, ex, depth + 1, false);
            out.push_back(std::move(child));
        }
    }
    node.children = std::move(out);
}

// A -D the scene never reads is most likely a typo (-D sppp=4 would otherwise render with the
// default spp without a word), so it is reported as an unused parameter is.
void check_defines_used(const std::vector<std::pair<std::string, std::string>>& defines,
                        const std::set<std::string>& scene_params, const std::string& file,
                        bool lenient) {
    const std::vector<std::string> names(scene_params.begin(), scene_params.end());
    for (const auto& [name, value] : defines) {
        if (scene_params.count(name)) continue;
        reject_unless_lenient(
            lenient, SourceLocation{},
            fmt::format("-D {}={}: {} has no parameter \"{}\"{}; its parameters (<default> "
                        "names and $names): {}",
                        name, value, file.empty() ? "the scene" : file, name,
                        did_you_mean(name, names), names.empty() ? "(none)" : join(names)));
    }
}

XmlNode run_passes(XmlNode scene, const std::vector<std::pair<std::string, std::string>>& defines,
                   const std::string& top_file, bool lenient) {
    std::error_code ec;
    const std::map<std::string, std::string> define_map(defines.begin(), defines.end());
    std::set<std::string> scene_params;
    Expansion ex{{}, define_map, define_map, scene_params, {}};
    ex.include_stack.push_back(top_file.empty() ? std::string()
                                                : fs::weakly_canonical(top_file, ec).string());
    set_root_dir(scene, scene.base_dir);
    expand(scene, ex, 1, true);
    substitute(scene, ex.params, scene_params);
    check_defines_used(defines, scene_params, top_file, lenient);
    scene.search_dirs = std::move(ex.search_dirs);
    return scene;
}

}  // namespace

FileSearch find_file(const XmlNode& node, const std::string& name,
                     const std::vector<std::string>& search_dirs) {
    FileSearch out;
    const fs::path p(name);
    if (p.is_absolute()) {
        out.path = name;
        out.found = entry_exists(p);
        return out;
    }
    std::vector<std::string> dirs = search_dirs;
    for (const std::string* d : {&node.base_dir, &node.root_dir})
        if (!d->empty() && std::find(dirs.begin(), dirs.end(), *d) == dirs.end())
            dirs.push_back(*d);
    for (const auto& dir : dirs) {
        const fs::path candidate = (fs::path(dir) / p).lexically_normal();
        out.searched.push_back(dir);
        if (entry_exists(candidate)) {
            out.path = candidate.string();
            out.found = true;
            return out;
        }
    }
    // None exists: name the candidate next to the file that named it.
    out.path = (fs::path(node.base_dir) / p).lexically_normal().string();
    return out;
}

std::string upgrade_parameter_name(const std::string& name) {
    if (auto it = kIrregularNames.find(name); it != kIrregularNames.end()) return it->second;
    std::string out;
    for (size_t i = 0; i < name.size(); ++i) {
        const char c = name[i];
        if (std::isupper(static_cast<unsigned char>(c))) {
            if (i > 0 && name[i - 1] != '_') out += '_';
            out += char(std::tolower(static_cast<unsigned char>(c)));
        } else {
            out += c;
        }
    }
    return out;
}

std::string upgrade_plugin_type(const std::string& tag, const std::string& type) {
    for (const auto& r : kTypeRenames)
        if (tag == r.tag && type == r.old_type) return r.new_type;
    return type;
}

XmlNode parse_scene_file(const std::string& path,
                         const std::vector<std::pair<std::string, std::string>>& defines,
                         bool lenient) {
    const std::string text = read_file(path, SourceLocation{});
    fs::path p(path);
    std::string base = p.parent_path().string();
    if (base.empty()) base = ".";
    return run_passes(parse_text(text, path, base, SourceLocation{}, 1), defines, path, lenient);
}

XmlNode parse_scene_string(const std::string& xml, const std::string& base_dir,
                           const std::vector<std::pair<std::string, std::string>>& defines,
                           bool lenient) {
    return run_passes(parse_text(xml, "<string>", base_dir, SourceLocation{}, 1), defines, "",
                      lenient);
}

}  // namespace femto::detail
