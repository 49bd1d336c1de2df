#include "plugin/registry.h"

#include <dlfcn.h>
#include <fmt/format.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>

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
    g_load_order.push_back(path);
    return g_by_path.emplace(path, LoadedPlugin{path, d}).first->second;
}

std::vector<std::string> available_types(const std::vector<std::string>& dirs) {
    std::vector<std::string> names;
    for (const auto& dir : dirs) {
        std::error_code ec;
        for (const auto& e : fs::directory_iterator(dir, ec))
            if (e.path().extension() == ".so") names.push_back(e.path().stem().string());
    }
    return names;
}

}  // namespace

std::vector<std::string> plugin_search_path(const std::vector<std::string>& extra_dirs) {
    std::vector<std::string> dirs;
    auto add = [&](const std::string& d) {
        if (d.empty()) return;
        std::error_code ec;
        if (!fs::is_directory(d, ec)) return;
        for (const auto& x : dirs)
            if (x == d) return;
        dirs.push_back(d);
    };
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
    for (const auto& d : extra_dirs) add(d);
    return dirs;
}

const PluginDescriptor& find_plugin(PluginKind kind, const std::string& type,
                                    const std::vector<std::string>& extra_dirs,
                                    const SourceLocation& loc) {
    // Said plainly rather than "corrected": every short plugin name is close to "".
    if (type.find_first_not_of(" \t\r\n") == std::string::npos)
        throw SceneError(loc, fmt::format("the <{}> type is empty: name a <{}> plugin (`femto "
                                          "plugins` lists them)",
                                          kind_tag(kind), kind_tag(kind)));
    std::lock_guard<std::mutex> lock(g_mutex);
    const auto dirs = plugin_search_path(extra_dirs);
    bool valid_name = true;
    for (char c : type)
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-'))
            valid_name = false;
    if (valid_name)
        for (const auto& dir : dirs) {
            const fs::path candidate = fs::path(dir) / (type + ".so");
            std::error_code ec;
            if (!fs::exists(candidate, ec)) continue;
            const LoadedPlugin& p = open_plugin(candidate.string(), loc);
            if (p.descriptor->kind != kind)
                throw SceneError(
                    loc, fmt::format("plugin \"{}\" ({}) is a <{}> plugin, but it is "
                                     "used as a <{}>",
                                     type, p.path, kind_tag(p.descriptor->kind), kind_tag(kind)));
            return *p.descriptor;
        }
    throw SceneError(
        loc, fmt::format("unknown <{}> plugin \"{}\"{}; searched: {}", kind_tag(kind), type,
                         did_you_mean(type, available_types(dirs)),
                         dirs.empty() ? std::string("(no plugin folder exists)") : join(dirs)));
}

std::vector<std::pair<std::string, const PluginDescriptor*>> list_plugins(
    const std::vector<std::string>& extra_dirs) {
    std::lock_guard<std::mutex> lock(g_mutex);
    std::vector<std::pair<std::string, const PluginDescriptor*>> out;
    std::map<std::string, bool> seen;
    for (const auto& dir : plugin_search_path(extra_dirs)) {
        std::vector<fs::path> files;
        std::error_code ec;
        for (const auto& e : fs::directory_iterator(dir, ec))
            if (e.path().extension() == ".so") files.push_back(e.path());
        std::sort(files.begin(), files.end());
        for (const auto& f : files) {
            if (seen[f.stem().string()]) continue;  // earlier folders win, as in find_plugin
            seen[f.stem().string()] = true;
            const LoadedPlugin& p = open_plugin(f.string(), SourceLocation{});
            out.emplace_back(p.path, p.descriptor);
        }
    }
    return out;
}

std::vector<std::string> loaded_plugin_files() {
    std::lock_guard<std::mutex> lock(g_mutex);
    return g_load_order;
}

}  // namespace femto::detail
