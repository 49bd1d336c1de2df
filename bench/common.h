// Shared by the benchmark programs in bench/ (header-only, every function inline): machine and
// load capture, medians, option splitting, and reading a film's cube back through its writer.
// (`femto bench` has its own, in host/src/bench/.)
#pragma once

#include <sys/resource.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "femto/host.h"
#include "femto/image_io.h"
#include "femto/scene.h"
#include "femto/sensor.h"

namespace femto_bench {

// -- machine -----------------------------------------------------------------------------------

/// The three load averages of /proc/loadavg ("1m 5m 15m"), or "unknown".
inline std::string read_loadavg() {
    std::ifstream f("/proc/loadavg");
    std::string a, b, c;
    if (!(f >> a >> b >> c)) return "unknown";
    return a + " " + b + " " + c;
}

/// "model name" of the first CPU in /proc/cpuinfo.
inline std::string cpu_model() {
    std::ifstream f("/proc/cpuinfo");
    for (std::string line; std::getline(f, line);)
        if (line.rfind("model name", 0) == 0) {
            const auto colon = line.find(':');
            if (colon == std::string::npos) break;
            std::string m = line.substr(colon + 1);
            m.erase(0, m.find_first_not_of(" \t"));
            return m;
        }
    return "unknown";
}

/// A field of /proc/self/status in kB (VmHWM = peak RSS, VmRSS = current), or -1.
inline long status_kb(const std::string& key) {
    std::ifstream f("/proc/self/status");
    for (std::string line; std::getline(f, line);)
        if (line.rfind(key + ":", 0) == 0) return std::stol(line.substr(key.size() + 1));
    return -1;
}

inline std::string now_utc() {
    const std::time_t t = std::time(nullptr);
    char buf[64];
    std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&t));
    return buf;
}

/// CPU time of the whole process (every thread), user + system, in seconds.
inline double cpu_seconds() {
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    auto sec = [](const timeval& t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); };
    return sec(ru.ru_utime) + sec(ru.ru_stime);
}

// -- small helpers -----------------------------------------------------------------------------

inline double median(std::vector<double> v) {
    if (v.empty()) return NAN;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Non-empty items of `s` separated by `sep`.
inline std::vector<std::string> split(const std::string& s, char sep) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    for (std::string item; std::getline(ss, item, sep);)
        if (!item.empty()) out.push_back(item);
    return out;
}

/// The value after option argv[i] (advancing i), for the benchmarks' option parsers.
inline std::string option_value(int argc, char** argv, int& i) {
    if (i + 1 >= argc) throw std::invalid_argument(std::string(argv[i]) + " needs a value");
    return argv[++i];
}

/// Reads "--name value" pairs: each name of `ints` takes a whole number, each of `strings` any
/// text. Throws std::invalid_argument on an unknown option or a missing or malformed value.
inline void parse_options(int argc, char** argv, const std::map<std::string, int*>& ints,
                          const std::map<std::string, std::string*>& strings) {
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (const auto it = ints.find(a); it != ints.end()) {
            const std::string v = option_value(argc, argv, i);
            size_t used = 0;
            *it->second = std::stoi(v, &used);
            if (used != v.size()) throw std::invalid_argument(a + ": not a whole number: " + v);
        } else if (const auto jt = strings.find(a); jt != strings.end()) {
            *jt->second = option_value(argc, argv, i);
        } else {
            throw std::invalid_argument("unknown option " + a);
        }
    }
}

// -- reading a film back ----------------------------------------------------------------------

/// The film's normalised cube [H][W][T][3], through its own writer (OUTBASE.npy, written to a
/// temporary folder). Needs libfemto_io.
inline std::vector<float> film_cube(femto::Scene& scene, const femto::RenderOptions& ro,
                                    const femto::RenderStats& st, std::vector<size_t>& shape) {
    namespace fs = std::filesystem;
    static int counter = 0;
    const fs::path tmp =
        fs::temp_directory_path() /
        ("femto_bench_cube_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
    fs::create_directories(tmp);
    femto::RenderInfo info = femto::make_render_info(scene, ro, st);
    info.write_npy = true;
    scene.sensor().film().write((tmp / "cube").string(), info);
    std::vector<float> cube = femto::io::read_npy((tmp / "cube.npy").string(), shape);
    fs::remove_all(tmp);
    return cube;
}

}  // namespace femto_bench
