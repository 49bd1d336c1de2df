// femto_bench_write: how fast and in how much memory a transient cube is written.
//
//  speed   A 256x256x256 cube rendered from the Cornell box (scenes/cornell-box, --spp
//          samples, normalised through the film's own .npy writer) is written, in
//          interleaved rounds, by
//          - baseline:   the layout femto wrote before the stacked frames, one EXR part per bin
//                        (ZIPS, one thread), reimplemented here as the yardstick;
//          - exr_<c>_t<n>: io::write_exr_cube with compression c (none, rle, zips, zip, piz)
//                        on OpenEXR's pool of n threads (1, 2);
//          - npy:        io::write_npy of the same cube;
//          - film / film_npy: everything `femto render` writes for this film (cube EXR, steady
//                        EXR, PNG; with --npy also the .npy), through Film::write.
//          Reports wall and CPU seconds and file sizes per run, medians and ratios to the
//          baseline. Files go to --tmp (default: the system temporary folder).
//  memory  Peak RSS (VmHWM) of child processes (this binary re-executed with --child): load the
//          Cornell box with a res x res film of `bins` bins, render 1 spp, write the film's
//          outputs; a 1-bin film of the same size is the baseline (program, scene, Embree).
//          Reports (peak - baseline) / cube size for the render and for render + write, for a
//          16x16 film from 2^8 to 2^20 bins and a 256x256 film of 256 bins.
//
// Output (folder --out): write_speed.csv (every run), write_speed_summary.csv (medians,
// ratios), write_memory.csv (every child), write_memory_summary.csv, write_meta.txt.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfThreading.h>
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include "common.h"
#include "femto/host.h"
#include "femto/image_io.h"
#include "femto/integrator.h"
#include "femto/scene.h"
#include "femto/sensor.h"

namespace fs = std::filesystem;
using namespace femto_bench;

namespace {

struct Options {
    std::string out_dir = std::string(FEMTO_BENCH_SOURCE_DIR) + "/bench/results";
    std::string tmp_dir = fs::temp_directory_path().string();
    std::vector<std::string> modes = {"speed", "memory"};
    int runs = 5, spp = 4;
    // child
    std::string child;
    int res = 16, bins = 256;
};

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&] { return option_value(argc, argv, i); };
        if (a == "--out")
            o.out_dir = next();
        else if (a == "--tmp")
            o.tmp_dir = next();
        else if (a == "--mode")
            o.modes = split(next(), ',');
        else if (a == "--runs")
            o.runs = std::stoi(next());
        else if (a == "--spp")
            o.spp = std::stoi(next());
        else if (a == "--child")
            o.child = next();
        else if (a == "--res")
            o.res = std::stoi(next());
        else if (a == "--bins")
            o.bins = std::stoi(next());
        else if (a == "--help") {
            fmt::print(
                "femto_bench_write [--out DIR] [--tmp DIR] [--mode speed,memory] [--runs N] "
                "[--spp N]\n");
            std::exit(0);
        } else
            throw std::invalid_argument("unknown option " + a);
    }
    return o;
}

std::string cornell_path() {
    return std::string(FEMTO_BENCH_SOURCE_DIR) + "/scenes/cornell-box/scene.xml";
}

std::unique_ptr<femto::Scene> load_cornell(int res, int bins, int spp) {
    femto::LoadOptions lo;
    lo.defines = {
        {"res", std::to_string(res)}, {"bins", std::to_string(bins)}, {"spp", std::to_string(spp)}};
    return femto::load_scene(cornell_path(), lo);
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// -- the yardstick: one EXR part per bin, as femto wrote cubes before ---------------------------

void write_parts_per_bin(const std::string& path, int w, int h, int bins, const float* data) {
    std::vector<Imf::Header> headers;
    for (int t = 0; t < bins; ++t) {
        Imf::Header hd(w, h);
        hd.compression() = Imf::ZIPS_COMPRESSION;
        hd.setName(fmt::format("t{:05}", t));
        hd.setType(Imf::SCANLINEIMAGE);
        for (const char* c : {"R", "G", "B"}) hd.channels().insert(c, Imf::Channel(Imf::FLOAT));
        headers.push_back(hd);
    }
    Imf::setGlobalThreadCount(0);
    Imf::MultiPartOutputFile file(path.c_str(), headers.data(), bins);
    const size_t xs = size_t(bins) * 3 * sizeof(float), ys = xs * size_t(w);
    for (int t = 0; t < bins; ++t) {
        Imf::OutputPart part(file, t);
        Imf::FrameBuffer fb;
        char* base = reinterpret_cast<char*>(const_cast<float*>(data + size_t(t) * 3));
        for (int c = 0; c < 3; ++c)
            fb.insert(std::string(1, "RGB"[c]),
                      Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys));
        part.setFrameBuffer(fb);
        part.writePixels(h);
    }
}

// -- speed ------------------------------------------------------------------------------------

struct Variant {
    std::string name;
    std::function<std::vector<std::string>(const std::string& base)> write;  // returns files
};

uintmax_t total_size(const std::vector<std::string>& files) {
    uintmax_t n = 0;
    for (const auto& f : files) n += fs::file_size(f);
    return n;
}

std::vector<Variant> variants(femto::Scene& scene, const femto::RenderInfo& info,
                              const std::vector<float>& cube, int res, int bins) {
    std::vector<Variant> v;
    v.push_back({"baseline", [&, res, bins](const std::string& base) {
                     write_parts_per_bin(base + ".exr", res, res, bins, cube.data());
                     return std::vector<std::string>{base + ".exr"};
                 }});
    for (const char* c : {"none", "rle", "zips", "zip", "piz"})
        for (int threads : {1, 2}) {
            femto::io::ExrCubeOptions opt;
            femto::io::parse_exr_compression(c, opt.compression);
            opt.threads = threads;
            v.push_back({fmt::format("exr_{}_t{}", c, threads),
                         [&, opt, res, bins](const std::string& base) {
                             femto::io::write_exr_cube(base + ".exr", res, res, bins, cube.data(),
                                                       nullptr, {}, nullptr, opt);
                             return std::vector<std::string>{base + ".exr"};
                         }});
        }
    v.push_back({"npy", [&, res, bins](const std::string& base) {
                     femto::io::write_npy(base + ".npy",
                                          {size_t(res), size_t(res), size_t(bins), 3}, cube.data());
                     return std::vector<std::string>{base + ".npy"};
                 }});
    for (bool npy : {false, true})
        v.push_back({npy ? "film_npy" : "film", [&scene, info, npy](const std::string& base) {
                         femto::RenderInfo i = info;
                         i.write_npy = npy;
                         return scene.sensor().film().write(base, i);
                     }});
    return v;
}

void speed(const Options& o, std::ostream& meta) {
    const int res = 256, bins = 256;
    auto scene = load_cornell(res, bins, o.spp);
    femto::RenderOptions ro;
    ro.spp = uint32_t(o.spp);
    const femto::RenderStats st = femto::render(*scene, ro);
    std::vector<size_t> shape;
    const std::vector<float> cube = film_cube(*scene, ro, st, shape);
    const femto::RenderInfo info = femto::make_render_info(*scene, ro, st);
    const double cube_mib = double(cube.size()) * sizeof(float) / (1 << 20);
    fmt::print("== speed: {}x{}x{} cube ({:.1f} MiB) of the Cornell box at {} spp, {} rounds\n",
               res, res, bins, cube_mib, o.spp, o.runs);
    const fs::path tmp = fs::path(o.tmp_dir) / fmt::format("femto_bench_write_{}", getpid());
    fs::create_directories(tmp);
    std::ofstream csv(o.out_dir + "/write_speed.csv");
    csv << "variant,round,wall_seconds,cpu_seconds,bytes\n";
    std::map<std::string, std::vector<double>> wall, cpu;
    std::map<std::string, uintmax_t> bytes;
    const std::vector<Variant> vs = variants(*scene, info, cube, res, bins);
    for (int round = 0; round < o.runs; ++round)
        for (const Variant& v : vs) {
            const std::string base = (tmp / v.name).string();
            const double c0 = cpu_seconds();
            const auto t0 = std::chrono::steady_clock::now();
            const std::vector<std::string> files = v.write(base);
            const double w = seconds_since(t0), c = cpu_seconds() - c0;
            bytes[v.name] = total_size(files);
            for (const auto& f : files) fs::remove(f);
            wall[v.name].push_back(w);
            cpu[v.name].push_back(c);
            csv << fmt::format("{},{},{:.4f},{:.4f},{}\n", v.name, round, w, c, bytes[v.name]);
            fmt::print("  round {} {:<14} {:6.3f} s wall {:6.3f} s cpu {:8.1f} MiB\n", round,
                       v.name, w, c, double(bytes[v.name]) / (1 << 20));
        }
    fs::remove_all(tmp);
    std::ofstream s(o.out_dir + "/write_speed_summary.csv");
    s << "variant,median_wall_seconds,median_cpu_seconds,mib,wall_ratio_to_baseline\n";
    const double base = median(wall["baseline"]);
    fmt::print("  {:<14} {:>9} {:>9} {:>9} {:>8}\n", "median", "wall s", "cpu s", "MiB", "÷ base");
    for (const Variant& v : vs) {
        const double w = median(wall[v.name]), c = median(cpu[v.name]);
        const double mib = double(bytes[v.name]) / (1 << 20);
        s << fmt::format("{},{:.4f},{:.4f},{:.2f},{:.4f}\n", v.name, w, c, mib, w / base);
        fmt::print("  {:<14} {:9.3f} {:9.3f} {:9.1f} {:8.3f}\n", v.name, w, c, mib, w / base);
        meta << fmt::format(
            "speed {}: median wall {:.3f} s, cpu {:.3f} s, {:.1f} MiB, {:.3f} x baseline\n", v.name,
            w, c, mib, w / base);
    }
}

// -- memory -----------------------------------------------------------------------------------

int memory_child(const Options& o) {
    auto scene = load_cornell(o.res, o.bins, 1);
    femto::RenderOptions ro;
    ro.spp = 1;
    const femto::RenderStats st = femto::render(*scene, ro);
    const long render_hwm = status_kb("VmHWM");
    const fs::path tmp = fs::path(o.tmp_dir) / fmt::format("femto_bench_write_mem_{}", getpid());
    fs::create_directories(tmp);
    const auto t0 = std::chrono::steady_clock::now();
    scene->sensor().film().write((tmp / "cube").string(), femto::make_render_info(*scene, ro, st));
    const double write_s = seconds_since(t0);
    fs::remove_all(tmp);
    fmt::print("peak_render_kb={} peak_write_kb={} render_s={:.3f} write_s={:.3f}\n", render_hwm,
               status_kb("VmHWM"), st.seconds, write_s);
    return 0;
}

std::map<std::string, double> run_child(const Options& o, int res, int bins) {
    const std::string self = fs::read_symlink("/proc/self/exe").string();
    const std::string cmd = fmt::format("'{}' --child memory --res {} --bins {} --tmp '{}'", self,
                                        res, bins, o.tmp_dir);
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) throw std::runtime_error("cannot run " + cmd);
    std::string out;
    char buf[512];
    while (std::fgets(buf, sizeof buf, p)) out += buf;
    if (pclose(p) != 0) throw std::runtime_error("child failed: " + cmd + "\n" + out);
    std::map<std::string, double> kv;
    const std::regex re(R"((\w+)=([0-9.]+))");
    for (std::sregex_iterator it(out.begin(), out.end(), re), end; it != end; ++it)
        kv[(*it)[1]] = std::stod((*it)[2]);
    return kv;
}

void memory(const Options& o, std::ostream& meta) {
    struct Case {
        int res, bins;
    };
    std::vector<Case> cases = {{256, 256}};
    for (int e = 8; e <= 20; e += 2) cases.push_back({16, 1 << e});
    fmt::print("== memory: peak RSS of render + write against the cube (child processes, 1 spp)\n");
    std::ofstream csv(o.out_dir + "/write_memory.csv");
    csv << "res,bins,cube_mib,baseline_mib,render_peak_mib,write_peak_mib,render_ratio,write_ratio,"
           "render_seconds,write_seconds\n";
    std::map<int, double> baseline;  // res -> peak of a 1-bin film, MiB
    for (const Case& c : cases) {
        if (!baseline.count(c.res))
            baseline[c.res] = run_child(o, c.res, 1)["peak_write_kb"] / 1024;
        const double base = baseline[c.res];
        const double cube_mib = double(c.res) * c.res * c.bins * 3 * 4 / (1 << 20);
        auto kv = run_child(o, c.res, c.bins);
        const double r = kv["peak_render_kb"] / 1024, w = kv["peak_write_kb"] / 1024;
        const double rr = (r - base) / cube_mib, wr = (w - base) / cube_mib;
        csv << fmt::format("{},{},{:.2f},{:.1f},{:.1f},{:.1f},{:.4f},{:.4f},{:.3f},{:.3f}\n", c.res,
                           c.bins, cube_mib, base, r, w, rr, wr, kv["render_s"], kv["write_s"]);
        fmt::print(
            "  {:>3}x{:<3} {:>7} bins cube {:8.1f} MiB  baseline {:6.1f}  render peak {:8.1f} "
            "({:.3f})  +write {:8.1f} ({:.3f})  write {:.2f} s\n",
            c.res, c.res, c.bins, cube_mib, base, r, rr, w, wr, kv["write_s"]);
        meta << fmt::format(
            "memory {}x{}x{}: cube {:.1f} MiB, (render peak - baseline)/cube {:.3f}, "
            "(write peak - baseline)/cube {:.3f}, write {:.2f} s\n",
            c.res, c.res, c.bins, cube_mib, rr, wr, kv["write_s"]);
    }
}

}  // namespace

int main(int argc, char** argv) {
    try {
        std::setvbuf(stdout, nullptr, _IOLBF, 0);
        const Options o = parse(argc, argv);
        if (!o.child.empty()) return memory_child(o);
        fs::create_directories(o.out_dir);
        std::ofstream meta(o.out_dir + "/write_meta.txt");
        meta << "date: " << now_utc() << "\ncpu: " << cpu_model()
             << "\nnproc: " << sysconf(_SC_NPROCESSORS_ONLN) << "\nbuild: " << FEMTO_BENCH_BUILD
             << "\nfemto: " << femto::version() << "\ntmp: " << o.tmp_dir
             << "\nload average at start: " << read_loadavg() << "\n";
        fmt::print("femto_bench_write: {} | {} cores | {} | load {}\n", cpu_model(),
                   sysconf(_SC_NPROCESSORS_ONLN), now_utc(), read_loadavg());
        for (const auto& m : o.modes) {
            if (m == "speed")
                speed(o, meta);
            else if (m == "memory")
                memory(o, meta);
            else
                throw std::invalid_argument("unknown mode " + m);
            meta << "load after " << m << ": " << read_loadavg() << "\n";
        }
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "femto_bench_write: %s\n", e.what());
        return 1;
    }
}
