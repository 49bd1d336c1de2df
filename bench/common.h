// Shared by the benchmarks in bench/ (header-only, every function inline): machine and load
// capture, medians, option splitting, scene text helpers, and the error measures of the
// error-against-time harnesses (relative MSE of a cube against a reference, with or without
// the reference's own variance taken out).
#pragma once

#include <sys/resource.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
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

/// The 1-minute load average, or -1.
inline double load1() {
    std::ifstream f("/proc/loadavg");
    double a = -1;
    f >> a;
    return a;
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

/// The integers of a comma-separated list ("16,64,256").
inline std::vector<int> int_list(const std::string& s) {
    std::vector<int> v;
    for (const auto& x : split(s, ',')) v.push_back(std::stoi(x));
    return v;
}

inline std::string read_text(const std::string& path) {
    std::ifstream f(path);
    if (!f) throw std::runtime_error("cannot read " + path);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

/// Replaces the single occurrence of `from` (throws when it is missing, so a changed scene
/// file fails loudly instead of silently benchmarking something else).
inline std::string replace_once(std::string text, const std::string& from, const std::string& to) {
    const size_t pos = text.find(from);
    if (pos == std::string::npos) throw std::runtime_error("scene text lacks: " + from);
    return text.replace(pos, from.size(), to);
}

/// Replaces from `begin` up to and including the next `end`.
inline std::string replace_block(std::string text, const std::string& begin, const std::string& end,
                                 const std::string& to) {
    const size_t a = text.find(begin);
    if (a == std::string::npos) throw std::runtime_error("scene text lacks: " + begin);
    const size_t b = text.find(end, a);
    if (b == std::string::npos) throw std::runtime_error("scene text lacks: " + end);
    return text.replace(a, b + end.size() - a, to);
}

// -- error measures ----------------------------------------------------------------------------

/// Sum of squared differences and of the reference's squares over a cube (any layout).
struct SquaredError {
    double se = 0;  ///< sum_v (x_v - r_v)^2
    double rr = 0;  ///< sum_v r_v^2
};

inline SquaredError squared_error(const std::vector<float>& x, const std::vector<float>& ref) {
    if (x.size() != ref.size()) throw std::runtime_error("cube sizes differ");
    SquaredError e;
    for (size_t i = 0; i < x.size(); ++i) {
        const double d = double(x[i]) - double(ref[i]);
        e.se += d * d;
        e.rr += double(ref[i]) * double(ref[i]);
    }
    return e;
}

/// relMSE = sum_v (x_v - r_v)^2 / sum_v r_v^2 over all voxels and channels v: the squared
/// relative L2 error of the whole cube (scale-free, no epsilon, dominated by bright voxels).
inline double rel_mse(const std::vector<float>& x, const std::vector<float>& ref) {
    const SquaredError e = squared_error(x, ref);
    return e.se / e.rr;
}

/// The same with the reference's own noise taken out: for x and r independent,
/// E[sum (x - r)^2] = sum (bias_x^2 + Var x) + sum Var r, so subtracting sum Var r (the
/// reference's variance estimate, `ref_var` summed) leaves the error of x against the truth.
inline double rel_mse_corrected(const std::vector<float>& x, const std::vector<float>& ref,
                                double ref_var_sum) {
    const SquaredError e = squared_error(x, ref);
    return (e.se - ref_var_sum) / e.rr;
}

// -- reading a film back ----------------------------------------------------------------------

/// The film's normalised cube [H][W][T][3], through its own writer (OUTBASE.npy, written to a
/// temporary folder). With `variance`, the film must have aovs="variance": OUTBASE_variance.npy
/// (the variance of each pixel-bin estimate) is read into it. With `count`, the film must have
/// aovs="count": OUTBASE_count.npy (contributions per pixel and bin, [H][W][T]) is read into
/// it. Needs libfemto_io.
inline std::vector<float> film_cube(femto::Scene& scene, const femto::RenderOptions& ro,
                                    const femto::RenderStats& st, std::vector<size_t>& shape,
                                    std::vector<float>* variance = nullptr,
                                    std::vector<float>* count = nullptr) {
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
    if (variance) {
        std::vector<size_t> vshape;
        *variance = femto::io::read_npy((tmp / "cube_variance.npy").string(), vshape);
        if (vshape != shape) throw std::runtime_error("variance and cube shapes differ");
    }
    if (count) {
        std::vector<size_t> cshape;
        *count = femto::io::read_npy((tmp / "cube_count.npy").string(), cshape);
        if (cshape.size() != 3 || !std::equal(cshape.begin(), cshape.end(), shape.begin()))
            throw std::runtime_error("count and cube shapes differ");
    }
    fs::remove_all(tmp);
    return cube;
}

}  // namespace femto_bench
