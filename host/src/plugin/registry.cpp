#include "plugin/registry.h"

#include <dlfcn.h>
#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>

#include "femto/log.h"
#include "util/strings.h"

namespace fs = std::filesystem;

namespace femto::detail {

namespace {

struct LoadedPlugin {
    std::string path;
    const PluginDescriptor* descriptor;
};

std::mutex g_mutex;
std::map<std::string, LoadedPlugin> g_by_path;  // libraries stay open for the process lifetime
std::vector<std::string> g_load_order;

// Folder holding this libfemto.
fs::path libfemto_dir() {
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&plugin_search_path), &info) == 0 || !info.dli_fname)
        return {};
    std::error_code ec;
    const fs::path lib = fs::canonical(info.dli_fname, ec);
    return ec ? fs::path() : lib.parent_path();
}

// The build tree's plugins belong to the build tree's libfemto only (not to an installed copy).
std::string build_dir_if_in_build_tree() {
    std::error_code ec;
    const fs::path build_lib = fs::weakly_canonical(FEMTO_BUILD_LIB_DIR, ec);
    return !ec && libfemto_dir() == build_lib ? std::string(FEMTO_BUILD_PLUGIN_DIR) : std::string();
}

std::string install_dir_near_libfemto() {
    const fs::path dir = libfemto_dir();
    return dir.empty() ? std::string() : (dir / FEMTO_PLUGIN_INSTALL_SUBDIR).string();
}

// Opens (or returns the cached) plugin at `path`; throws SceneError on ABI problems.
const LoadedPlugin& open_plugin(const std::string& path, const SourceLocation& loc) {
    if (auto it = g_by_path.find(path); it != g_by_path.end()) return it->second;
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) throw SceneError(loc, fmt::format("cannot load plugin {}: {}", path, dlerror()));
    auto fn =
        reinterpret_cast<femto_plugin_descriptor_fn>(dlsym(handle, "femto_plugin_descriptor"));
    if (!fn) {
        dlclose(handle);
        throw SceneError(loc, fmt::format("{} is not a femto plugin: it does not export "
                                          "femto_plugin_descriptor",
                                          path));
    }
    const PluginDescriptor* d = fn();
    if (!d || d->abi_version != kPluginAbiVersion) {
        const unsigned found = d ? d->abi_version : 0;
        dlclose(handle);
        throw SceneError(loc, fmt::format("plugin {} was built for plugin ABI version {}, but this "
                                          "femto expects version {}: rebuild it against the "
                                          "installed femto headers",
                                          path, found, kPluginAbiVersion));
    }
    // A type is found by its file name, so the two must agree (a library copied under another
    // name would otherwise stand in for a type it does not implement).
    if (fs::path(path).stem().string() != d->type_name) {
        const std::string declared = d->type_name;
        dlclose(handle);
        throw SceneError(loc, fmt::format("plugin {} declares the type \"{}\": a plugin library "
                                          "must be named after its type ({}.so)",
                                          path, declared, declared));
    }
    g_load_order.push_back(path);
    return g_by_path.emplace(path, LoadedPlugin{path, d}).first->second;
}

// The types in `dirs` (their libraries' file names without .so), sorted, each once.
std::vector<std::string> available_types(const std::vector<std::string>& dirs) {
    std::set<std::string> names;
    for (const auto& dir : dirs) {
        std::error_code ec;
        for (const auto& e : fs::directory_iterator(dir, ec))
            if (e.path().extension() == ".so") names.insert(e.path().stem().string());
    }
    return {names.begin(), names.end()};
}

// Every library for `type` in `dirs`, in search order: the first one is used.
std::vector<std::string> libraries_of_type(const std::string& type,
                                           const std::vector<std::string>& dirs) {
    std::vector<std::string> found;
    for (const auto& dir : dirs) {
        const fs::path candidate = fs::path(dir) / (type + ".so");
        std::error_code ec;
        if (fs::exists(candidate, ec)) found.push_back(candidate.string());
    }
    return found;
}

// A type provided by several libraries (a plugin of one's own named like a built-in one, or
// the same plugin in two folders) is said once per process, naming the library used and the
// ones ignored: otherwise the only symptom is an unexpected parameter error or image.
void report_shadowed(const std::string& type, const std::vector<std::string>& libraries) {
    static std::set<std::string> reported;  // guarded by g_mutex
    if (libraries.size() < 2 || !reported.insert(join(libraries)).second) return;
    log_warning(fmt::format(
        "plugin type \"{}\" is provided by {} libraries: using {}, ignoring {} (the first on the "
        "plugin search path wins: --plugin-dir folders in the order given, then femto's own "
        "plugins, then $FEMTO_PLUGIN_PATH)",
        type, libraries.size(), libraries.front(), join({libraries.begin() + 1, libraries.end()})));
}

// An explicitly named plugin folder that is missing or not a folder is a mistake, not an
// empty folder.
void require_plugin_folder(const std::string& dir) {
    std::error_code ec;
    const fs::file_status status = fs::status(dir, ec);
    if (!fs::exists(status))
        throw SceneError(fmt::format("plugin folder \"{}\" (--plugin-dir) does not exist", dir));
    if (!fs::is_directory(status))
        throw SceneError(fmt::format(
            "plugin folder \"{}\" (--plugin-dir) is not a folder: give the folder that holds the "
            "plugin libraries (<type>.so)",
            dir));
}

}  // namespace

std::vector<std::string> plugin_search_path(const std::vector<std::string>& extra_dirs) {
    std::vector<std::string> dirs;
    std::vector<fs::path> canonical;  // the same folder named twice is searched once
    auto add = [&](const std::string& d) {
        if (d.empty()) return;
        std::error_code ec;
        if (!fs::is_directory(d, ec)) return;
        const fs::path c = fs::weakly_canonical(d, ec);
        if (std::find(canonical.begin(), canonical.end(), c) != canonical.end()) return;
        canonical.push_back(c);
        dirs.push_back(d);
    };
    // Folders named explicitly come first, so that a plugin of one's own replaces a built-in
    // plugin of the same type; $FEMTO_PLUGIN_PATH only adds types.
    for (const auto& d : extra_dirs) {
        require_plugin_folder(d);
        add(d);
    }
    add(build_dir_if_in_build_tree());
    add(install_dir_near_libfemto());
    if (const char* env = std::getenv("FEMTO_PLUGIN_PATH")) {
        std::string s = env;
        size_t start = 0;
        while (start <= s.size()) {
            const size_t end = s.find(':', start);
            add(s.substr(start, end == std::string::npos ? std::string::npos : end - start));
            if (end == std::string::npos) break;
            start = end + 1;
        }
    }
    return dirs;
}

const PluginDescriptor& find_plugin(PluginKind kind, const std::string& type,
                                    const std::vector<std::string>& extra_dirs,
                                    const SourceLocation& loc) {
    // Said plainly rather than "corrected": every short plugin name is close to "".
    if (type.find_first_not_of(" \t\r\n") == std::string::npos)
        throw SceneError(loc, fmt::format("the <{}> type is empty: name {} plugin (`femto "
                                          "plugins` lists them)",
                                          kind_tag(kind), tag_with_article(kind)));
    std::lock_guard<std::mutex> lock(g_mutex);
    const auto dirs = plugin_search_path(extra_dirs);
    bool valid_name = true;
    for (char c : type)
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-'))
            valid_name = false;
    const std::vector<std::string> libraries =
        valid_name ? libraries_of_type(type, dirs) : std::vector<std::string>();
    if (libraries.empty())
        throw SceneError(
            loc, fmt::format("unknown <{}> plugin \"{}\"{}; searched: {}", kind_tag(kind), type,
                             did_you_mean(type, available_types(dirs)),
                             dirs.empty() ? std::string("(no plugin folder exists)") : join(dirs)));
    report_shadowed(type, libraries);
    const LoadedPlugin& p = open_plugin(libraries.front(), loc);
    if (p.descriptor->kind != kind)
        throw SceneError(
            loc, fmt::format("plugin \"{}\" ({}) is {} plugin, but it is used as {}", type, p.path,
                             tag_with_article(p.descriptor->kind), tag_with_article(kind)));
    return *p.descriptor;
}

std::vector<std::pair<std::string, const PluginDescriptor*>> list_plugins(
    const std::vector<std::string>& extra_dirs) {
    std::lock_guard<std::mutex> lock(g_mutex);
    const auto dirs = plugin_search_path(extra_dirs);
    std::vector<std::pair<std::string, const PluginDescriptor*>> out;
    for (const std::string& type : available_types(dirs)) {
        const std::vector<std::string> libraries = libraries_of_type(type, dirs);
        report_shadowed(type, libraries);
        const LoadedPlugin& p = open_plugin(libraries.front(), SourceLocation{});
        out.emplace_back(p.path, p.descriptor);
    }
    return out;
}

std::vector<std::string> loaded_plugin_files() {
    std::lock_guard<std::mutex> lock(g_mutex);
    return g_load_order;
}

}  // namespace femto::detail
