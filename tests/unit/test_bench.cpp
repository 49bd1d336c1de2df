// `femto bench` (issue 12 §1): the error measures against hand-computed values, the log-log fit
// and equal-error ratio against data with known answers, the experiment reader's located errors,
// and a whole study end to end: rows, report, plot, resuming, stopping, a changed experiment.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "bench/experiment.h"
#include "bench/measures.h"
#include "bench/runner.h"
#include "femto/error.h"
#include "femto/testing/render.h"
#include "util/strings.h"

namespace fs = std::filesystem;
using namespace femto::bench;

namespace {

// A 1 x 2 cube of 3 bins (centres 0.5, 1.5, 2.5) and one channel.
Cube cube_of(std::vector<float> data) {
    Cube c;
    c.H = 1, c.W = 2, c.T = 3, c.C = 1, c.start = 0, c.bin_width = 1;
    c.data = std::move(data);
    return c;
}

void write(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

std::string read(const fs::path& p) {
    std::ifstream in(p);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Options of a study written into `out`, without a line per run.
RunnerOptions quiet_into(const fs::path& out) {
    RunnerOptions o;
    o.out_dir = out.string();
    o.progress = false;
    return o;
}

// A plane at z = 0 lit by a small rectangular lamp above it, seen from z = 4 by `film` (max_depth
// 3 for `integrator`, which may be "$integrator" of a <default> in `head`).
std::string lit_plane(const std::string& integrator, const std::string& film,
                      const std::string& head = "") {
    return "<scene version=\"3.0.0\">" + head + "<integrator type=\"" + integrator +
           "\"><integer name=\"max_depth\" value=\"3\"/></integrator><sensor "
           "type=\"perspective\"><transform name=\"to_world\"><lookat origin=\"0,0,4\" "
           "target=\"0,0,0\" up=\"0,1,0\"/></transform>" +
           film +
           "</sensor><shape type=\"rectangle\"><transform name=\"to_world\"><scale "
           "value=\"3\"/></transform></shape><shape type=\"rectangle\"><transform "
           "name=\"to_world\"><scale value=\"0.3\"/><rotate x=\"1\" angle=\"180\"/><translate "
           "z=\"1\"/></transform><emitter type=\"area\"><rgb name=\"radiance\" "
           "value=\"10\"/></emitter></shape></scene>";
}

std::string load_error(const fs::path& p) {
    try {
        load_experiment(p.string());
    } catch (const femto::SceneError& e) {
        return e.what();
    }
    ADD_FAILURE() << "no error for " << p;
    return {};
}

}  // namespace

TEST(BenchMeasures, FormulasOnAHandComputedCube) {
    //           pixel 0: bins 0 1 2      pixel 1: bins 0 1 2
    const Cube ref = cube_of({1, 2, 0, 4, 0, 0});
    const Cube x = cube_of({2, 2, 1, 3, 0, 0});
    // Whole cube: squared differences 1 + 0 + 1 + 1 = 3 over 1 + 4 + 16 = 21.
    EXPECT_DOUBLE_EQ(rel_mse(x, ref), 3.0 / 21.0);
    // Bins with centres in [0, 1): bin 0 only: (1 + 1) / (1 + 16).
    EXPECT_DOUBLE_EQ(rel_mse(x, ref, 0, 1), 2.0 / 17.0);
    // Per pixel: pixel 0 (1 + 0 + 1) / (1 + 4), pixel 1 1 / 16; their mean.
    EXPECT_DOUBLE_EQ(pixel_rel_mse(x, ref, -1e9, 1e9), 0.5 * (2.0 / 5.0 + 1.0 / 16.0));
    EXPECT_DOUBLE_EQ(pixel_profile_rel_mse(x, ref, 0, 0), 2.0 / 5.0);
    EXPECT_EQ(pixel_profile(x, 1, 0), (std::vector<double>{3, 0, 0}));
    EXPECT_THROW(pixel_profile(x, 2, 0), std::runtime_error);
    const std::vector<double> frames = frame_rel_mse(x, ref);
    ASSERT_EQ(frames.size(), 3u);
    EXPECT_DOUBLE_EQ(frames[0], 2.0 / 17.0);
    EXPECT_DOUBLE_EQ(frames[1], 0.0);
    EXPECT_TRUE(std::isnan(frames[2]));  // a black reference frame has no relative error
    EXPECT_DOUBLE_EQ(energy_error(x, ref), (8.0 - 7.0) / 7.0);
    Cube other = ref;
    other.T = 2;
    EXPECT_THROW(rel_mse(x, other), std::runtime_error);
    // With the reference's variance known, it is taken out of the squared differences:
    // (3 - (0.5 + 0.25)) / 21 for the cube, (1 - 0.5 + 1 - 0.25) / 17 for bin 0.
    Cube noisy = ref;
    noisy.variance = {0.5f, 0, 0, 0.25f, 0, 0};
    EXPECT_DOUBLE_EQ(rel_mse(x, noisy), 2.25 / 21.0);
    EXPECT_DOUBLE_EQ(rel_mse(x, noisy, 0, 1), 1.25 / 17.0);
    EXPECT_DOUBLE_EQ(frame_rel_mse(x, noisy)[0], 1.25 / 17.0);
    EXPECT_DOUBLE_EQ(rel_mse(x, without_variance(noisy)), 3.0 / 21.0);
    // The mean over resolved frames: the lit frames 0 and 1 (frame 2 is black), each weighing
    // the same: (2/17 + 0) / 2. A frame whose reference noise is 5 % or more of its energy is
    // not resolved: Var r = 1 in frame 0 (sum r^2 = 17) leaves frame 1 alone.
    EXPECT_DOUBLE_EQ(resolved_frame_rel_mse(x, ref), 1.0 / 17.0);
    Cube unresolved = ref;
    unresolved.variance = {1, 0, 0, 0, 0, 0};
    EXPECT_DOUBLE_EQ(resolved_frame_rel_mse(x, unresolved), 0.0);
    unresolved.variance = {1, 1, 0, 0, 0, 0};  // frame 1: noise 1 of 4: none resolved
    EXPECT_TRUE(std::isnan(resolved_frame_rel_mse(x, unresolved)));
}

// results.csv and raw_rays.csv cells: every comma splits, so an empty cell and a cell cut
// short stay visible in the count.
TEST(BenchCsv, CellsSplitAtEveryComma) {
    using femto::detail::split;
    EXPECT_EQ(split("a,b,c", ','), (std::vector<std::string>{"a", "b", "c"}));
    EXPECT_EQ(split("a,,b,", ','), (std::vector<std::string>{"a", "", "b", ""}));
    EXPECT_EQ(split("", ','), (std::vector<std::string>{""}));
}

TEST(BenchMeasures, PairedThroughputRatio) {
    // b runs at exactly twice a's rate in every pair, whatever the machine's drift: every
    // resample gives 2.
    const Ratio r = paired_median_ratio({1, 2, 3, 4, 5}, {2, 4, 6, 8, 10});
    EXPECT_DOUBLE_EQ(r.value, 2.0);
    EXPECT_DOUBLE_EQ(r.lo, 2.0);
    EXPECT_DOUBLE_EQ(r.hi, 2.0);
    // Ratios 1, 2, 3: their median, inside an interval within the ratios' range.
    const Ratio spread = paired_median_ratio({1, 1, 1}, {3, 1, 2});
    EXPECT_DOUBLE_EQ(spread.value, 2.0);
    EXPECT_GE(spread.lo, 1.0);
    EXPECT_LE(spread.hi, 3.0);
    EXPECT_LT(spread.lo, spread.hi);
    EXPECT_TRUE(std::isnan(paired_median_ratio({1, 2}, {1, 2}).lo));  // too few pairs
    EXPECT_DOUBLE_EQ(median({4, 1, 3, 2}), 2.5);
}

TEST(BenchMeasures, LogLogFitRecoversAKnownSlope) {
    // error = 3 t^-0.8 exactly: slope -0.8, no spread.
    std::vector<double> t, e;
    for (double s : {0.1, 0.4, 1.6, 6.4}) t.push_back(s), e.push_back(3 * std::pow(s, -0.8));
    Fit f = fit_log_log(t, e);
    EXPECT_NEAR(f.slope, -0.8, 1e-12);
    EXPECT_NEAR(f.slope_ci95, 0, 1e-9);
    EXPECT_NEAR(f.seconds_at(3), 1, 1e-9);
    // With log-normal noise (sigma 0.2) the 95 % interval covers the true slope in about 95 %
    // of 400 studies; 88 % is 5 standard deviations of a binomial below 95 %.
    std::mt19937_64 rng(5);
    std::normal_distribution<double> noise(0, 0.2);
    int covered = 0;
    for (int k = 0; k < 400; ++k) {
        t.clear(), e.clear();
        for (double s : {0.1, 0.2, 0.4, 0.8, 1.6, 3.2})
            for (int seed = 0; seed < 3; ++seed)
                t.push_back(s), e.push_back(std::pow(s, -1.0) * std::exp(noise(rng)));
        f = fit_log_log(t, e);
        covered += std::abs(f.slope + 1) <= f.slope_ci95;
    }
    EXPECT_GT(covered, 0.88 * 400) << covered;
    EXPECT_LT(covered, 400);  // an interval that always covers is too wide
    EXPECT_NEAR(student_t975(10), 2.228, 1e-3);
    EXPECT_NEAR(student_t975(1000), 1.962, 1e-3);
}

TEST(BenchMeasures, EqualErrorRatioOfATwiceFasterVariant) {
    // B reaches every error A reaches in half the time: the ratio is 0.5, within its interval.
    std::mt19937_64 rng(9);
    std::normal_distribution<double> noise(0, 0.1);
    std::vector<double> ta, ea, tb, eb;
    for (double s : {0.1, 0.3, 1.0, 3.0})
        for (int seed = 0; seed < 4; ++seed) {
            ta.push_back(s), ea.push_back(std::exp(noise(rng)) / s);
            tb.push_back(s / 2), eb.push_back(std::exp(noise(rng)) / s);
        }
    const Ratio r = equal_error_ratio(ta, ea, tb, eb);
    EXPECT_NEAR(r.value, 0.5, 0.1);
    EXPECT_LT(r.lo, 0.5);
    EXPECT_GT(r.hi, 0.5);
    EXPECT_LT(r.hi, 1.0);  // and it tells the two apart
}

TEST(BenchExperiment, BadInputIsALocatedError) {
    const fs::path dir = femto::testing::temp_dir("bench-experiment");
    write(dir / "scene.xml", "<scene version=\"3.0.0\"/>");
    const std::string head = "<experiment>\n<scene file=\"scene.xml\"/>\n";
    const std::string rest =
        "<variant name=\"a\"/>\n<budgets spp=\"1 4\"/>\n<reference variant=\"a\" spp=\"8\"/>\n";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {head + rest + "<budget spp=\"3\"/>\n</experiment>",
         ":6:1: unknown element <budget> in <experiment>"},
        {head + "<variant name=\"a\"/>\n<budgets spp=\"1 x\"/>\n</experiment>",
         ":4:1: <budgets> spp: \"x\" is not a finite number"},
        {head + "<variant name=\"a\"/>\n<budgets spp=\"0\"/>\n</experiment>",
         ":4:1: <budgets> spp: 0 is not a whole number from 1"},
        {head + "<variant name=\"a\"/>\n<budgets spp=\"1\" seconds=\"2\"/>\n</experiment>",
         "needs either spp=\"...\" or seconds=\"...\""},
        {head + "<variant name=\"a\"/>\n<budgets spp=\"1\"/>\n<metric name=\"relmse\"/>\n"
                "</experiment>",
         ":5:1: <metric> needs a <reference>"},
        {head + "<variant name=\"a\"/>\n<budgets spp=\"1\"/>\n<window name=\"w\" start=\"0\" "
                "end=\"1\"/>\n</experiment>",
         ":5:1: <window> and <pixel> measure errors: they need a <reference>"},
        {head + rest + "<metric name=\"window:late\"/>\n</experiment>",
         ":6:1: <metric> name \"window:late\": valid: relmse, pixel_relmse, frame_relmse"},
        {head + rest + "<metric name=\"relmse\"/>\n<metric name=\"relmse\"/>\n</experiment>",
         ":7:1: <metric> \"relmse\" is named twice"},
        {head + "<variant name=\"a\"/>\n<budgets spp=\"1\"/>\n<reference variant=\"a\" "
                "spp=\"4\" scene=\"nope\"/>\n</experiment>",
         ":5:1: <reference> names scene \"nope\", which is not declared"},
        {head + rest + "<raw_rays seconds=\"0\"/>\n</experiment>",
         ":6:1: <raw_rays> seconds: 0 is not in [0.01, 3600]"},
        {head + rest + "<isolation value=\"fork\"/>\n</experiment>",
         ":6:1: <isolation> value \"fork\": valid: none"},
        {head + "<variant name=\"a\"/>\n<budgets spp=\"1\"/>\n<reference variant=\"b\" "
                "spp=\"4\"/>\n</experiment>",
         ":5:1: <reference> names variant \"b\", which is not declared"},
        {"<experiment>\n<scene file=\"nothere.xml\"/>\n</experiment>",
         ":2:1: file \"nothere.xml\" does not exist"},
        {head + "<variant name=\"a\" integrator=\"path\"/>\n</experiment>",
         ":3:1: <variant> has no attribute \"integrator\""},
        {head + "<variant name=\"a\"/><variant name=\"a\"/>\n</experiment>",
         "two variants are named \"a\""},
        {head + "<variant name=\"a\"/>\n<budgets spp=\"4 8 4\"/>\n</experiment>",
         ":4:1: <budgets> lists a budget twice"},
        {head + rest + "<seeds count=\"2\"/>\n<seeds count=\"3\"/>\n</experiment>",
         ":7:1: a second <seeds>"},
        {head + rest + "<seeds values=\"1 1000003\"/>\n</experiment>",
         ":5:1: run seed 1000003 is one of the reference's two halves' seeds"},
        {head + "<variant name=\"a\"/>\n<pixel name=\"p\" x=\"-1\" y=\"0\"/>\n</experiment>",
         ":4:1: <pixel> x: -1 is not a whole number from 0"},
        {head + "<variant name=\"a, b\"/>\n</experiment>",
         ":3:1: <variant> name \"a, b\": a name may not hold ,"},
        {"<experiment>\n<scene file=\"scene.xml\">\n</experiment>", ":3:3: malformed XML"},
        {"<scene version=\"3.0.0\"/>", ":1:1: the root element is <scene>, not <experiment>"},
    };
    for (const auto& [text, expected] : cases) {
        write(dir / "e.xml", text);
        const std::string message = load_error(dir / "e.xml");
        EXPECT_NE(message.find(expected), std::string::npos) << message << "\nfor\n" << text;
    }
    fs::remove_all(dir);
}

// A whole study on a small scene: 2 variants x 2 budgets x 2 seeds. Every run is a row; the
// report and plot are written; a second run resumes (nothing to render); a stopped run keeps
// the rows it has; a changed experiment file is refused in the old folder.
TEST(BenchRunner, RunsResumesStopsAndRefusesAChangedExperiment) {
    const fs::path dir = femto::testing::temp_dir("bench-runner");
    write(dir / "scene.xml",
          lit_plane("$integrator",
                    "<film type=\"transient\"><integer name=\"width\" value=\"8\"/><integer "
                    "name=\"height\" value=\"8\"/><float name=\"start\" value=\"3\"/><float "
                    "name=\"bin_width\" value=\"0.5\"/><integer name=\"bins\" "
                    "value=\"10\"/></film>",
                    "<default name=\"integrator\" value=\"transient_path\"/>"));
    const std::string experiment =
        "<experiment name=\"t\"><scene file=\"scene.xml\" name=\"plane\"/>"
        "<variant name=\"path\"/><variant name=\"bdpt\"><define name=\"integrator\" "
        "value=\"transient_bdpt\"/></variant><budgets spp=\"2 8\"/><seeds count=\"2\"/>"
        "<reference variant=\"path\" spp=\"64\"/><window name=\"early\" start=\"3\" end=\"5\"/>"
        "<pixel name=\"centre\" x=\"4\" y=\"4\"/><metric name=\"pixel:centre\"/><metric "
        "name=\"frame_relmse\"/>"
        "<threads value=\"1\"/></experiment>";
    write(dir / "e.xml", experiment);
    const Experiment e = load_experiment((dir / "e.xml").string());
    RunnerOptions o = quiet_into(dir / "out");
    std::atomic<bool> stop{true};  // stopped before the first run: nothing is measured
    o.stop = &stop;
    EXPECT_FALSE(run_experiment(e, o));
    EXPECT_TRUE(read_results((dir / "out" / "results.csv").string(), e).empty());
    stop = false;
    EXPECT_TRUE(run_experiment(e, o));
    const std::vector<RunRow> rows = read_results((dir / "out" / "results.csv").string(), e);
    ASSERT_EQ(rows.size(), 8u);
    for (const RunRow& r : rows) {
        EXPECT_TRUE(r.budget == "2" || r.budget == "8");
        EXPECT_EQ(std::to_string(r.spp), r.budget);
        EXPECT_GT(r.rel_mse, 0);
        EXPECT_LT(r.rel_mse, 10);
        ASSERT_EQ(r.windows.size(), 1u);
        ASSERT_EQ(r.pixels.size(), 1u);
        EXPECT_GT(r.pixels[0], 0);  // the centre pixel sees the lit plane
        EXPECT_GT(r.frame_rel_mse, 0);
        EXPECT_EQ(r.samples, uint64_t(r.spp) * 64);
    }
    EXPECT_EQ(rows[0].variant, "path");  // interleaved: path, bdpt, path, bdpt, ...
    EXPECT_EQ(rows[1].variant, "bdpt");
    for (const char* f :
         {"report.md", "plot.svg", "frames.csv", "profiles.csv", "reference_profiles_plane.csv"})
        EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
    const std::string report = read(dir / "out" / "report.md");
    EXPECT_NE(report.find("| median Mrays/s |"), std::string::npos) << report;
    // Each <metric> is fitted in its own table.
    for (const char* table :
         {"### pixel:centre\n\n| variant | runs | slope of pixel:centre vs time",
          "### frame_relmse\n\n| variant | runs | slope of frame_relmse vs time"})
        EXPECT_NE(report.find(table), std::string::npos) << table << "\n" << report;
    for (const char* row : {"| path | 4 (4 fitted) | ", "| bdpt | 4 (4 fitted) | "})
        EXPECT_NE(report.find(row), std::string::npos) << row << "\n" << report;
    int cached = 0;  // the reference's two halves: their mean and its variance
    for (const auto& f : fs::directory_iterator(dir / "out" / "cache")) {
        const std::string name = f.path().filename().string();
        cached += name.find("-mean.npy") != std::string::npos ||
                  name.find("-variance.npy") != std::string::npos;
    }
    EXPECT_EQ(cached, 2);
    for (const RunRow& r : rows) EXPECT_LT(r.rel_mse, r.rel_mse_raw);  // its noise taken out
    // Resuming: nothing left to run, the rows stay as they were.
    EXPECT_TRUE(run_experiment(e, o));
    EXPECT_EQ(read_results((dir / "out" / "results.csv").string(), e).size(), 8u);
    // More seeds: the study resumes, rendering only the new runs (4 more rows).
    std::string more = experiment;
    const std::string two_seeds = "<seeds count=\"2\"/>";
    more.replace(more.find(two_seeds), two_seeds.size(), "<seeds count=\"3\"/>");
    write(dir / "e.xml", more);
    EXPECT_TRUE(run_experiment(load_experiment((dir / "e.xml").string()), o));
    EXPECT_EQ(read_results((dir / "out" / "results.csv").string(), e).size(), 12u);
    // A row cut short by a kill is dropped on resume, and its run renders again.
    {
        const fs::path csv = dir / "out" / "results.csv";
        std::string text;
        {
            std::ifstream in(csv);
            text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        }
        text.resize(text.size() - 7);  // the last row loses its end
        std::ofstream(csv, std::ios::trunc) << text;
    }
    EXPECT_EQ(read_results((dir / "out" / "results.csv").string(), e).size(), 11u);
    EXPECT_TRUE(run_experiment(load_experiment((dir / "e.xml").string()), o));
    EXPECT_EQ(read_results((dir / "out" / "results.csv").string(), e).size(), 12u);
    // The experiment changed beyond its seeds and budgets: its rows must not mix with the old.
    std::string changed = more;
    const std::string bdpt = "value=\"transient_bdpt\"";
    changed.replace(changed.find(bdpt), bdpt.size(), "value=\"transient_light\"");
    write(dir / "e.xml", changed);
    EXPECT_THROW(run_experiment(load_experiment((dir / "e.xml").string()), o), femto::SceneError);
    // The same with a thread count other than the one the rows were measured with.
    write(dir / "e.xml", more);
    RunnerOptions two = o;
    two.threads = 2;
    EXPECT_THROW(run_experiment(load_experiment((dir / "e.xml").string()), two), femto::SceneError);
    fs::remove_all(dir);
}

// Time budgets: each becomes the sample count that fills it (from a calibration render), so
// every pixel of a run has its full samples; a larger budget gets more samples.
TEST(BenchRunner, TimeBudgetsBecomeSampleCounts) {
    const fs::path dir = femto::testing::temp_dir("bench-timed");
    write(dir / "scene.xml",
          "<scene version=\"3.0.0\"><integrator type=\"path\"/><sensor type=\"perspective\">"
          "<film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer "
          "name=\"height\" value=\"16\"/></film></sensor><shape type=\"rectangle\"><transform "
          "name=\"to_world\"><rotate x=\"1\" angle=\"180\"/><translate z=\"2\"/></transform>"
          "<emitter type=\"area\"/></shape>"
          "</scene>");
    write(dir / "e.xml",
          "<experiment><scene file=\"scene.xml\" name=\"s\"/><variant name=\"v\"/><budgets "
          "seconds=\"0.02 0.2\"/><reference variant=\"v\" spp=\"16\"/><threads value=\"1\"/>"
          "</experiment>");
    const Experiment e = load_experiment((dir / "e.xml").string());
    RunnerOptions o = quiet_into(dir / "out");
    ASSERT_TRUE(run_experiment(e, o));
    const std::vector<RunRow> rows = read_results((dir / "out" / "results.csv").string(), e);
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_GE(rows[0].spp, 1u);
    EXPECT_GT(rows[1].spp, rows[0].spp);
    // A directly seen emitter: every pixel is exact whatever its samples, so no pixel was left
    // without samples (a stopped render would leave some black).
    EXPECT_LT(rows[0].rel_mse_raw, 1e-10);
    fs::remove_all(dir);
}

// <isolation value="process"/>: each run renders in a `femto bench-run` child process, whose
// peak memory is measured: a film with a cube of 32 x 32 x 1536 bins x RGB (its float32 copy
// alone is 18.9 MB) peaks well above a 1-bin film.
// Without a <reference> the study measures throughput: no errors, no plot.
TEST(BenchRunner, ChildProcessesMeasurePeakMemoryWithoutAReference) {
    const fs::path dir = femto::testing::temp_dir("bench-child");
    write(dir / "scene.xml",
          "<scene version=\"3.0.0\"><default name=\"bins\" value=\"1\"/>"
          "<integrator type=\"transient_path\"><integer name=\"max_depth\" value=\"2\"/>"
          "</integrator><sensor type=\"perspective\"><film type=\"transient\"><integer "
          "name=\"width\" value=\"32\"/><integer name=\"height\" value=\"32\"/><float "
          "name=\"start\" value=\"0\"/><float name=\"bin_width\" value=\"0.01\"/><integer "
          "name=\"bins\" value=\"$bins\"/></film></sensor><shape type=\"rectangle\"><transform "
          "name=\"to_world\"><rotate x=\"1\" angle=\"180\"/><translate z=\"2\"/></transform>"
          "<emitter type=\"area\"/></shape></scene>");
    write(dir / "e.xml",
          "<experiment><scene file=\"scene.xml\" name=\"s\"/><variant name=\"one-bin\"/>"
          "<variant name=\"cube\"><define name=\"bins\" value=\"1536\"/></variant><budgets "
          "spp=\"1 2\"/><seeds count=\"2\"/><isolation value=\"process\"/><threads value=\"1\"/>"
          "</experiment>");
    const Experiment e = load_experiment((dir / "e.xml").string());
    EXPECT_TRUE(e.child_processes);
    EXPECT_FALSE(e.has_reference());
    RunnerOptions o = quiet_into(dir / "out");
    o.executable = FEMTO_CLI_PATH;
    ASSERT_TRUE(run_experiment(e, o));
    const std::vector<RunRow> rows = read_results((dir / "out" / "results.csv").string(), e);
    ASSERT_EQ(rows.size(), 8u);
    double one_bin = 0, cube = INFINITY;
    for (const RunRow& r : rows) {
        EXPECT_EQ(r.samples, uint64_t(r.spp) * 32 * 32);
        EXPECT_GT(r.rays, 0u);
        EXPECT_TRUE(std::isnan(r.rel_mse));
        // CPU time over wall clock; these renders last a few clock ticks, too short to bound it.
        EXPECT_TRUE(std::isfinite(r.cores_used) && r.cores_used >= 0) << r.cores_used;
        ASSERT_TRUE(std::isfinite(r.peak_mb));
        if (r.variant == "one-bin") one_bin = std::max(one_bin, r.peak_mb);
        if (r.variant == "cube") cube = std::min(cube, r.peak_mb);
    }
    // At least half the cube's float32 copy: the rest of each peak overlaps what the 1-bin run
    // peaks at elsewhere (loading), and pages of the film no sample reached are never resident.
    EXPECT_GT(cube - one_bin, 0.5 * 32 * 32 * 1536 * 3 * 4 / (1 << 20)) << cube << " " << one_bin;
    const std::string report = read(dir / "out" / "report.md");
    EXPECT_NE(report.find("| variant | runs | median samples/s | samples/s vs `one-bin`"),
              std::string::npos)
        << report;
    EXPECT_NE(report.find("median peak MB"), std::string::npos);
    EXPECT_FALSE(fs::exists(dir / "out" / "plot.svg"));
    EXPECT_FALSE(fs::exists(dir / "out" / "frames.csv"));
    // A scene value the loader refuses is found before anything runs, naming the variant.
    write(dir / "e.xml",
          "<experiment><scene file=\"scene.xml\" name=\"s\"/><variant name=\"bad\"><define "
          "name=\"bins\" value=\"-3\"/></variant><budgets spp=\"1\"/><isolation "
          "value=\"process\"/></experiment>");
    o.out_dir = (dir / "bad").string();
    try {
        run_experiment(load_experiment((dir / "e.xml").string()), o);
        ADD_FAILURE() << "no error";
    } catch (const femto::SceneError& err) {
        EXPECT_NE(std::string(err.what()).find("variant \"bad\" cannot render scene \"s\""),
                  std::string::npos)
            << err.what();
        EXPECT_NE(std::string(err.what()).find("bins must be in"), std::string::npos) << err.what();
    }
    EXPECT_FALSE(fs::exists(dir / "bad"));
    // A child that fails while rendering (a filter wider than femto's tiles allow, refused by
    // the render, not the loader) is an error naming the run.
    std::string wide = read(dir / "scene.xml");
    wide.replace(wide.find("</film>"), 7,
                 "<rfilter type=\"gaussian\"><float name=\"stddev\" value=\"20\"/></rfilter>"
                 "</film>");
    write(dir / "wide.xml", wide);
    write(dir / "e.xml",
          "<experiment><scene file=\"wide.xml\" name=\"s\"/><variant name=\"wide\"/><budgets "
          "spp=\"1\"/><isolation value=\"process\"/></experiment>");
    o.out_dir = (dir / "wide").string();
    try {
        run_experiment(load_experiment((dir / "e.xml").string()), o);
        ADD_FAILURE() << "no error";
    } catch (const femto::SceneError& err) {
        EXPECT_NE(std::string(err.what()).find("failed with exit code 2"), std::string::npos)
            << err.what();
    }
    fs::remove_all(dir);
}

// <raw_rays>: Embree's own rate in the scene's geometry, each kind of ray measured before each
// (budget, seed) group (none when resuming has nothing to run), and every run's ray rate
// against it in the report.
TEST(BenchRunner, RawRaysMeasureEmbreeBeforeEachGroup) {
    const fs::path dir = femto::testing::temp_dir("bench-raw");
    write(dir / "scene.xml",
          lit_plane("path",
                    "<film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer "
                    "name=\"height\" value=\"16\"/></film>"));
    write(dir / "e.xml",
          "<experiment><scene file=\"scene.xml\" name=\"s\"/><variant name=\"v\"/><budgets "
          "spp=\"1 2\"/><seeds count=\"2\"/><raw_rays seconds=\"0.05\"/><threads "
          "value=\"1\"/></experiment>");
    const Experiment e = load_experiment((dir / "e.xml").string());
    RunnerOptions o = quiet_into(dir / "out");
    ASSERT_TRUE(run_experiment(e, o));
    std::ifstream csv(dir / "out" / "raw_rays.csv");
    std::string line;
    std::getline(csv, line);
    EXPECT_EQ(line, "scene,budget,seed,kind,rays,seconds,cores_used");
    int rows = 0;
    while (std::getline(csv, line)) {
        ++rows;
        std::vector<std::string> f;
        std::stringstream ss(line);
        for (std::string cell; std::getline(ss, cell, ',');) f.push_back(cell);
        ASSERT_EQ(f.size(), 7u) << line;
        EXPECT_GE(std::stod(f[5]), 0.05) << line;        // at least the asked time
        EXPECT_GE(std::stoull(f[4]), 1u << 20) << line;  // at least one pass over the rays
    }
    EXPECT_EQ(rows, 2 * 2 * 3);  // (budget, seed) groups x kinds
    const std::string report = read(dir / "out" / "report.md");
    EXPECT_NE(report.find("Embree's raw rate"), std::string::npos) << report;
    EXPECT_NE(report.find("rays/s vs Embree's raw incoherent"), std::string::npos) << report;
    // Resuming with nothing left to run measures nothing more.
    ASSERT_TRUE(run_experiment(e, o));
    std::ifstream again(dir / "out" / "raw_rays.csv");
    EXPECT_EQ(
        std::count(std::istreambuf_iterator<char>(again), std::istreambuf_iterator<char>(), '\n'),
        1 + rows);
    fs::remove_all(dir);
}

// <reference scene="..."/>: one scene's reference for every scene (a scene at several scales
// against its unit scale): rendered once, and the same scene measured twice under two names
// gives the same errors.
TEST(BenchRunner, OneScenesReferenceServesEveryScene) {
    const fs::path dir = femto::testing::temp_dir("bench-ref-scene");
    write(dir / "scene.xml",
          lit_plane("path",
                    "<film type=\"hdrfilm\"><integer name=\"width\" value=\"8\"/><integer "
                    "name=\"height\" value=\"8\"/></film>"));
    write(dir / "e.xml",
          "<experiment><scene file=\"scene.xml\" name=\"a\"/><scene file=\"scene.xml\" "
          "name=\"b\"/><variant name=\"v\"/><budgets spp=\"2\"/><reference variant=\"v\" "
          "spp=\"64\" scene=\"a\"/><threads value=\"1\"/></experiment>");
    const Experiment e = load_experiment((dir / "e.xml").string());
    RunnerOptions o = quiet_into(dir / "out");
    ASSERT_TRUE(run_experiment(e, o));
    int cached = 0;
    for (const auto& f : fs::directory_iterator(dir / "out" / "cache"))
        cached += f.path().filename().string().find("reference-a-") == 0;
    EXPECT_EQ(cached, 2);  // its mean and variance, nothing for b
    const std::vector<RunRow> rows = read_results((dir / "out" / "results.csv").string(), e);
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_EQ(rows[0].scene, "a");
    EXPECT_DOUBLE_EQ(rows[0].rel_mse, rows[1].rel_mse);  // same render, same reference
    fs::remove_all(dir);
}
