// report.md and plot.svg of `femto bench`. The plot is a few dozen SVG elements written by
// hand: a plotting library would be a heavier dependency than the plot (docs/bench.md).
#include "bench/report.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "bench/measures.h"
#include "femto/host.h"
#include "io/atomic_file.h"
#include "util/strings.h"

namespace fs = std::filesystem;

namespace femto::bench {

namespace {

std::string first_line_of(const char* path, const std::string& prefix = "") {
    std::ifstream in(path);
    for (std::string line; std::getline(in, line);)
        if (prefix.empty() || line.rfind(prefix, 0) == 0)
            return prefix.empty() ? line : line.substr(line.find(':') + 2);
    return "unknown";
}

std::string load_average() {
    std::istringstream in(first_line_of("/proc/loadavg"));
    std::string a, b, c;
    in >> a >> b >> c;
    return a + " " + b + " " + c;
}

// Writes `text` to `path` through femto's atomic-write helpers, so a reader never sees half a
// report.
void write_atomically(const fs::path& path, const std::string& text) {
    const std::string tmp = io::detail::temp_path_for(path.string());
    {
        std::ofstream out(tmp);
        out << text;
        out.close();
        if (out.fail()) {
            fs::remove(tmp);
            throw SceneError(fmt::format("cannot write \"{}\"", path.string()));
        }
    }
    io::detail::commit_file(tmp, path.string());
}

// A run's error `metric` (a results.csv column named by a <metric>).
double metric_of(const Experiment& e, const std::string& metric, const RunRow& r) {
    if (metric == "pixel_relmse") return r.pixel_rel_mse;
    if (metric == "frame_relmse") return r.frame_rel_mse;
    for (size_t i = 0; i < e.windows.size(); ++i)
        if (metric == "window:" + e.windows[i].name) return r.windows[i];
    for (size_t i = 0; i < e.pixels.size(); ++i)
        if (metric == "pixel:" + e.pixels[i].name) return r.pixels[i];
    return r.rel_mse;
}

struct Series {
    std::vector<double> seconds, samples, errors, cores_used, peak_mb;
    // Samples and rays per second of each run, by "budget seed": what pairs it with the runs of
    // other variants (and Embree's raw rate) measured just before or after it.
    std::map<std::string, double> rate_of_run, ray_rate_of_run;
    std::map<std::string, std::vector<double>> by_budget;
};

// The median of a run-keyed map's values.
double median_of(const std::map<std::string, double>& by_run) {
    std::vector<double> values;
    for (const auto& [run, value] : by_run) values.push_back(value);
    return median(std::move(values));
}

// The runs of one scene, by variant (in the experiment's order), with their error `metric`.
std::vector<std::pair<std::string, Series>> series_of(const Experiment& e,
                                                      const std::vector<RunRow>& rows,
                                                      const std::string& scene,
                                                      const std::string& metric) {
    std::vector<std::pair<std::string, Series>> out;
    for (const Variant& v : e.variants) {
        Series s;
        for (const RunRow& r : rows) {
            if (r.scene != scene || r.variant != v.name) continue;
            s.seconds.push_back(r.seconds);
            s.samples.push_back(double(r.samples));
            s.errors.push_back(metric_of(e, metric, r));
            if (r.seconds > 0) {
                const std::string run = r.budget + " " + std::to_string(r.seed);
                s.rate_of_run[run] = double(r.samples) / r.seconds;
                s.ray_rate_of_run[run] = double(r.rays) / r.seconds;
            }
            if (std::isfinite(r.cores_used)) s.cores_used.push_back(r.cores_used);
            if (std::isfinite(r.peak_mb)) s.peak_mb.push_back(r.peak_mb);
            s.by_budget[r.budget].push_back(metric_of(e, metric, r));
        }
        out.emplace_back(v.name, std::move(s));
    }
    return out;
}

std::string g(double v) { return std::isfinite(v) ? fmt::format("{:.3g}", v) : "–"; }

std::string ratio_text(const Ratio& r) {
    return fmt::format("{} [{}, {}]", g(r.value), g(r.lo), g(r.hi));
}

// Embree's raw rate in one scene (raw_rays.csv, <raw_rays>): rays per second of each kind of
// ray, and of the incoherent ones by (budget, seed) group, to pair with the runs.
struct RawRates {
    std::map<std::string, std::vector<double>> by_kind;
    std::map<std::string, double> incoherent_of_run;
    bool empty() const { return by_kind.empty(); }
};

// Every scene's raw rates, from raw_rays.csv (rows `scene, budget, seed, kind, rays, seconds,
// cores_used`); none when the study measured none.
std::map<std::string, RawRates> read_raw_rates(const fs::path& csv) {
    std::map<std::string, RawRates> by_scene;
    std::ifstream in(csv);
    std::string line;
    std::getline(in, line);  // the header
    while (std::getline(in, line)) {
        const std::vector<std::string> f = detail::split(line, ',');
        if (f.size() != 7) continue;  // cut short by a kill
        const double seconds = std::atof(f[5].c_str());
        if (!(seconds > 0)) continue;
        const double rate = std::atof(f[4].c_str()) / seconds;
        RawRates& raw = by_scene[f[0]];
        raw.by_kind[f[3]].push_back(rate);
        if (f[3] == "incoherent") raw.incoherent_of_run[f[1] + " " + f[2]] = rate;
    }
    return by_scene;
}

// The columns every table has: throughput against the first variant, rays (against Embree's
// raw rate, when measured), cores and memory.
std::string throughput_header(const Experiment& e, const RawRates& raw) {
    return fmt::format(
        " samples/s vs `{}`, run by run (95 %) | median Mrays/s |{} median cores used |{}",
        e.variants.front().name,
        raw.empty() ? "" : " rays/s vs Embree's raw incoherent, run by run (95 %) |",
        e.child_processes ? " median peak MB |" : "");
}

// The separator row under a table's `header`: one cell per column.
std::string separator_row(const std::string& header) {
    std::string row = "|";
    for (size_t i = 1; i < size_t(std::count(header.begin(), header.end(), '|')); ++i)
        row += "---|";
    return row + "\n";
}

// The median of b / a over the runs both hold (keys "budget seed"): runs of one group ran one
// after the other, so a drift of the machine's speed cancels.
Ratio paired_ratio(const std::map<std::string, double>& a_of_run,
                   const std::map<std::string, double>& b_of_run) {
    std::vector<double> a, b;
    for (const auto& [run, value] : b_of_run)
        if (auto it = a_of_run.find(run); it != a_of_run.end())
            a.push_back(it->second), b.push_back(value);
    return paired_median_ratio(a, b);
}

std::string throughput_cells(const Experiment& e, const RawRates& raw, const Series& base,
                             const Series& s) {
    return fmt::format(
        " {} | {} |{} {} |{}", ratio_text(paired_ratio(base.rate_of_run, s.rate_of_run)),
        g(median_of(s.ray_rate_of_run) * 1e-6),
        raw.empty()
            ? ""
            : " " + ratio_text(paired_ratio(raw.incoherent_of_run, s.ray_rate_of_run)) + " |",
        g(median(s.cores_used)), e.child_processes ? " " + g(median(s.peak_mb)) + " |" : "");
}

// A study without a reference: throughput and memory only.
std::string throughput_section(const Experiment& e, const RawRates& raw,
                               const std::vector<std::pair<std::string, Series>>& series) {
    const std::string header = "| variant | runs | median samples/s |" + throughput_header(e, raw);
    std::string md = header + "\n" + separator_row(header);
    for (const auto& [name, s] : series)
        md += fmt::format("| {} | {} | {} |", name, s.seconds.size(), g(median_of(s.rate_of_run))) +
              throughput_cells(e, raw, series.front().second, s) + "\n";
    return md + "\n";
}

// Embree's raw rates of a scene, medians of each kind of ray.
std::string raw_rates_line(const RawRates& raw) {
    std::string md =
        "Embree's raw rate (`<raw_rays>`, random rays in the scene's geometry, Embree "
        "alone), median Mrays/s:";
    for (const char* kind : {"incoherent", "sorted", "shadow"})
        if (auto it = raw.by_kind.find(kind); it != raw.by_kind.end())
            md += fmt::format(" {} {} ({} measurements);", kind, g(median(it->second) * 1e-6),
                              it->second.size());
    md.back() = '.';
    return md + "\n\n";
}

// One scene's table for one error metric.
std::string metric_table(const Experiment& e, const std::vector<RunRow>& rows,
                         const SceneSpec& scene, const RawRates& raw, const std::string& metric) {
    const auto series = series_of(e, rows, scene.name, metric);
    const std::vector<std::string> budgets = e.budget_labels();
    const std::string& base_name = e.variants.front().name;
    std::string header = fmt::format(
        "| variant | runs | slope of {0} vs time (95 %) | time to equal {0} vs `{1}` (95 %) | "
        "samples to equal {0} vs `{1}` (95 %) |{2}",
        metric, base_name, throughput_header(e, raw));
    for (const std::string& b : budgets)
        header += fmt::format(" median {} @ {}{} |", metric, b, e.timed() ? " s" : " spp");
    std::string md = header + "\n" + separator_row(header);
    const Series& base = series.front().second;
    for (const auto& [name, s] : series) {
        // One budget leaves only timing noise along the time axis: no slope, no ratio.
        const bool fits = budgets.size() >= 2;
        const Fit f = fits ? fit_log_log(s.seconds, s.errors) : Fit{NAN, NAN, NAN, 0};
        const Ratio none{NAN, NAN, NAN};
        const Ratio time =
            fits ? equal_error_ratio(base.seconds, base.errors, s.seconds, s.errors) : none;
        const Ratio samples =
            fits ? equal_error_ratio(base.samples, base.errors, s.samples, s.errors) : none;
        md += fmt::format("| {} | {} ({} fitted) | {} ± {} | {} | {} |", name, s.seconds.size(),
                          f.n, g(f.slope), g(f.slope_ci95), ratio_text(time), ratio_text(samples)) +
              throughput_cells(e, raw, base, s);
        for (const std::string& b : budgets) {
            auto it = s.by_budget.find(b);
            md += " " + (it == s.by_budget.end() ? std::string("–") : g(median(it->second))) + " |";
        }
        md += "\n";
    }
    return md + "\n";
}

std::string scene_section(const Experiment& e, const std::vector<RunRow>& rows,
                          const SceneSpec& scene, const RawRates& raw) {
    std::string md = fmt::format("## {}\n\n`{}`\n\n", scene.name, scene.file);
    if (!raw.empty()) md += raw_rates_line(raw);
    if (!e.has_reference())
        return md + throughput_section(e, raw, series_of(e, rows, scene.name, "relmse"));
    for (const std::string& metric : e.metrics)
        md += (e.metrics.size() > 1 ? fmt::format("### {}\n\n", metric) : std::string()) +
              metric_table(e, rows, scene, raw, metric);
    return md;
}

// ---- plot.svg --------------------------------------------------------------------------------

constexpr const char* kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd",
                                    "#ff7f0e", "#8c564b", "#e377c2", "#17becf"};

std::string svg_panel(const Experiment& e, const std::vector<RunRow>& rows, const SceneSpec& scene,
                      double y0) {
    const auto series = series_of(e, rows, scene.name, e.metrics.front());
    double x_lo = INFINITY, x_hi = -INFINITY, y_lo = INFINITY, y_hi = -INFINITY;
    for (const auto& [name, s] : series)
        for (size_t i = 0; i < s.seconds.size(); ++i)
            if (s.seconds[i] > 0 && s.errors[i] > 0 && std::isfinite(s.errors[i])) {
                x_lo = std::min(x_lo, std::log10(s.seconds[i]));
                x_hi = std::max(x_hi, std::log10(s.seconds[i]));
                y_lo = std::min(y_lo, std::log10(s.errors[i]));
                y_hi = std::max(y_hi, std::log10(s.errors[i]));
            }
    std::string out = fmt::format(
        "<text x=\"70\" y=\"{}\" font-size=\"14\">{}: {} against render seconds</text>\n", y0 + 20,
        scene.name, e.metrics.front());
    if (!(x_hi >= x_lo))
        return out + fmt::format("<text x=\"70\" y=\"{}\">no runs</text>\n", y0 + 60);
    x_lo = std::floor(x_lo), x_hi = std::max(x_lo + 1, std::ceil(x_hi));
    y_lo = std::floor(y_lo), y_hi = std::max(y_lo + 1, std::ceil(y_hi));
    const double left = 70, top = y0 + 35, w = 480, h = 260;
    auto px = [&](double lx) { return left + (lx - x_lo) / (x_hi - x_lo) * w; };
    auto py = [&](double ly) { return top + (y_hi - ly) / (y_hi - y_lo) * h; };
    out += fmt::format(
        "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" "
        "stroke=\"black\"/>\n",
        left, top, w, h);
    for (double d = x_lo; d <= x_hi + 1e-9; ++d)
        out += fmt::format(
            "<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" "
            "text-anchor=\"middle\">1e{}</text>\n",
            px(d), top + h + 15, int(d));
    for (double d = y_lo; d <= y_hi + 1e-9; ++d)
        out += fmt::format(
            "<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" "
            "text-anchor=\"end\">1e{}</text>\n",
            left - 5, py(d) + 4, int(d));
    for (size_t k = 0; k < series.size(); ++k) {
        const auto& [name, s] = series[k];
        const char* colour = kColours[k % std::size(kColours)];
        double lo = INFINITY, hi = -INFINITY;
        for (size_t i = 0; i < s.seconds.size(); ++i) {
            if (!(s.seconds[i] > 0 && s.errors[i] > 0 && std::isfinite(s.errors[i]))) continue;
            const double lx = std::log10(s.seconds[i]);
            lo = std::min(lo, lx), hi = std::max(hi, lx);
            out += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.5\" fill=\"{}\"/>\n",
                               px(lx), py(std::log10(s.errors[i])), colour);
        }
        const Fit f = e.budget_labels().size() >= 2 ? fit_log_log(s.seconds, s.errors)
                                                    : Fit{NAN, NAN, NAN, 0};
        if (std::isfinite(f.slope) && hi > lo) {
            auto fit_y = [&](double lx) {
                return (f.intercept + f.slope * lx * std::log(10.0)) / std::log(10.0);
            };
            out += fmt::format(
                "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" "
                "stroke=\"{}\" stroke-width=\"1.5\"/>\n",
                px(lo), py(fit_y(lo)), px(hi), py(fit_y(hi)), colour);
        }
        out += fmt::format(
            "<text x=\"{}\" y=\"{}\" font-size=\"12\" fill=\"{}\">{} (slope "
            "{} ± {})</text>\n",
            left + w + 15, top + 15 + 18 * double(k), colour, name, g(f.slope), g(f.slope_ci95));
    }
    return out;
}

}  // namespace

Machine Machine::now(int threads) {
    Machine m;
    char host[256] = {};
    if (gethostname(host, sizeof host - 1) == 0) m.host = host;
    m.cpu = first_line_of("/proc/cpuinfo", "model name");
    m.cores = std::thread::hardware_concurrency();
    m.threads = threads;
    m.femto_version = version();
    const std::time_t t = std::time(nullptr);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&t));
    m.date = buf;
    m.load_before = load_average();
    return m;
}

std::string Machine::describe() const {
    return fmt::format("{} ({}, {} cores, load average {} before)", host, cpu, cores, load_before);
}

Machine Machine::finish() const {
    Machine m = *this;
    m.load_after = load_average();
    return m;
}

void write_report(const Experiment& e, const std::vector<RunRow>& rows, const Machine& machine,
                  const fs::path& dir) {
    std::string md = fmt::format("# {}\n\n", e.name);
    md += fmt::format(
        "Experiment `{}` (digest {}), femto {}. Machine: {}, {} cores, {} threads; {}; load "
        "average {} before, {} after the last session's runs. {}; time: the render alone, wall "
        "clock; samples: camera samples (spp x pixels); cores used: the render's CPU time over "
        "its wall clock{}.\n\n",
        e.file, e.digest, machine.femto_version, machine.cpu, machine.cores,
        machine.threads > 0 ? std::to_string(machine.threads) : std::string("all"), machine.date,
        machine.load_before, machine.load_after,
        e.has_reference() ? fmt::format("Errors: `{}` (docs/bench.md)", detail::join(e.metrics))
                          : std::string("No reference: throughput only"),
        e.child_processes ? "; peak MB: each run's child process's peak resident memory "
                            "(loading, rendering and writing the film's outputs)"
                          : "");
    if (machine.workers.size() > 1)
        md += fmt::format(
            "Distributed study: the runs went to {} workers (one process per machine unless "
            "`--runs-per-machine` said more), each (scene, budget, seed) group to one of them: "
            "{}. The machine above is rank 0's.\n\n",
            machine.workers.size(), detail::join(machine.workers, "; "));
    const std::map<std::string, RawRates> raw = read_raw_rates(dir / "raw_rays.csv");
    for (const SceneSpec& scene : e.scenes) {
        const auto found = raw.find(scene.name);
        md += scene_section(e, rows, scene, found == raw.end() ? RawRates{} : found->second);
    }
    md += e.has_reference() ? "Rows: `results.csv` (one per run), per-frame errors: `frames.csv`, "
                              "plot: `plot.svg`.\n"
                            : "Rows: `results.csv` (one per run).\n";
    write_atomically(dir / "report.md", md);
    if (!e.has_reference()) return;  // no errors to plot

    const double panel = 330;
    std::string svg = fmt::format(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"800\" height=\"{}\" "
        "font-family=\"sans-serif\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
        panel * double(e.scenes.size()) + 10);
    for (size_t i = 0; i < e.scenes.size(); ++i)
        svg += svg_panel(e, rows, e.scenes[i], panel * double(i));
    write_atomically(dir / "plot.svg", svg + "</svg>\n");
}

}  // namespace femto::bench
