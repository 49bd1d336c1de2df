#include "fuzz_common.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string_view>
#include <typeinfo>

#include "femto/error.h"
#include "femto/host.h"
#include "femto/properties.h"

namespace femto::fuzz {
namespace {

namespace fs = std::filesystem;

// libFuzzer runs inputs one at a time in one thread: plain counters suffice.
uint64_t g_accepted = 0, g_located = 0;
std::string g_scratch;

// Printed at exit (libFuzzer exits normally after -runs, -max_total_time or a corpus replay):
// how many inputs were accepted and how many ended in a located error, which the CLI turns
// into exit code 2. scripts/fuzz.sh reads this line.
void print_tally() {
    const uint64_t total = g_accepted + g_located;
    std::fprintf(stderr,
                 "femto-fuzz tally: %llu inputs, %llu accepted, %llu located errors (exit 2), "
                 "%.1f%% located\n",
                 static_cast<unsigned long long>(total),
                 static_cast<unsigned long long>(g_accepted),
                 static_cast<unsigned long long>(g_located),
                 total ? 100.0 * static_cast<double>(g_located) / static_cast<double>(total) : 0.0);
    if (!g_scratch.empty()) {
        std::error_code ec;
        fs::remove_all(g_scratch, ec);
    }
}

void register_tally() {
    static const bool registered = [] { return std::atexit(print_tally) == 0; }();
    (void)registered;
}

[[noreturn]] void finding(const char* what, const char* message) {
    std::fprintf(stderr, "femto-fuzz finding: %s: %s\n", what, message);
    std::abort();
}

void count_located(const SceneError& e) {
    ++g_located;
    // For looking at what the readers say about a corpus (docs/fuzzing.md).
    static const bool verbose = std::getenv("FEMTO_FUZZ_VERBOSE") != nullptr;
    if (verbose) std::fprintf(stderr, "femto-fuzz error: %s\n", e.what());
}

// Runs `body`; a SceneError goes to `on_error`, anything else thrown is a finding.
void classify(const std::function<void()>& body,
              const std::function<void(const SceneError&)>& on_error) {
    register_tally();
    try {
        body();
        ++g_accepted;
    } catch (const SceneError& e) {
        on_error(e);
    } catch (const std::exception& e) {
        finding(typeid(e).name(), e.what());
    } catch (...) {
        finding("an exception of unknown type", "");
    }
}

}  // namespace

void run(const std::function<void()>& load) {
    classify(load, [](const SceneError& e) {
        if (e.location().file.empty()) finding("a SceneError without a location", e.what());
        count_located(e);
    });
}

void run_file(const std::string& path, const std::function<void()>& read,
              const std::function<void()>& then) {
    bool reading = true;
    classify(
        [&] {
            read();
            reading = false;
            if (then) then();
        },
        [&](const SceneError& e) {
            if (reading && std::string_view(e.what()).find(path) == std::string_view::npos)
                finding("an error that does not name the file", e.what());
            count_located(e);
        });
}

const std::string& scratch_dir() {
    if (g_scratch.empty()) {
        register_tally();
        const fs::path dir =
            fs::temp_directory_path() / ("femto-fuzz-" + std::to_string(::getpid()));
        fs::create_directories(dir);
        g_scratch = dir.string();
    }
    return g_scratch;
}

std::string write_scratch(const std::string& name, const uint8_t* data, size_t size) {
    const fs::path path = fs::path(scratch_dir()) / name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (!out) finding("cannot write the scratch file", path.c_str());
    return path.string();
}

void read_plugin_file(PluginKind kind, const std::string& type, const std::string& parameter,
                      const std::string& file_name, const uint8_t* data, size_t size) {
    const std::string path = write_scratch(file_name, data, size);
    run([&] {
        Properties props(type, {"fuzz.xml", 1, 1});
        props.set(parameter, Properties::Type::String, path, {"fuzz.xml", 2, 5});
        create_object(kind, type, props);
    });
}

}  // namespace femto::fuzz
