// The connection and angular time-sampling strategies of thesis ch. 5.6.2-5.6.3 (issue 5, §3):
//  - chi-square tests of each strategy plugin's samples against its pdf, and the pdf's
//    integral (tests/unit/chi2.h);
//  - Fig. 5.7 (middle and right) as tests: line-to-point connection times and time-angular
//    path times are uniform over their ranges, while the steady strategies' are not;
//  - unbiasedness: in a foggy box with multiple scattering, every combination of distance,
//    connection and angular strategy, with and without MIS, renders the same cube as the
//    steady strategies within noise, and its time integral equals the steady `path` render.
//    (The closed-form single-scattering checks with these strategies are in test_media.cpp.)
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "chi2.h"
#include "cube_util.h"
#include "femto/host.h"
#include "femto/medium.h"
#include "femto/random.h"
#include "femto/time_sampling.h"
#include "scene_util.h"
#include "vol_util.h"

using namespace femto;
using namespace femto_test;

namespace {

std::shared_ptr<ConnectionSampler> make_connection(const std::string& type) {
    Properties props(type, {});
    return std::static_pointer_cast<ConnectionSampler>(
        create_object(PluginKind::Connection, type, props));
}

std::shared_ptr<AngularSampler> make_angular(const std::string& type) {
    Properties props(type, {});
    return std::static_pointer_cast<AngularSampler>(
        create_object(PluginKind::Angular, type, props));
}

std::shared_ptr<PhaseFunction> make_phase_function(const std::string& type, double g = 0) {
    Properties props(type, {});
    if (type == "hg") props.set_float("g", g);
    return std::static_pointer_cast<PhaseFunction>(create_object(PluginKind::Phase, type, props));
}

struct ConnectionCase {
    const char* name;
    Vec3 target;
    double length;  // may be infinite
};

// Targets beside, behind, nearly ahead on the line (where line-to-point's density almost
// vanishes before the target), far off a short segment; segments finite and infinite.
const ConnectionCase kConnectionCases[] = {
    {"beside", Vec3(2.f, 1.f, 0.f), 5.0},
    {"behind", Vec3(-1.f, 0.5f, 0.3f), 3.0},
    {"nearly_ahead", Vec3(3.f, 0.05f, 0.f), 6.0},
    {"far_short", Vec3(1.f, 4.f, 2.f), 0.7},
    {"beside_infinite", Vec3(2.f, 1.f, 0.f), kInfinity},
};

ConnectionQuery query_of(const ConnectionCase& c) {
    // A segment from (0.1, -0.2, 0.3) along +x, so no coordinate is special.
    return ConnectionQuery{Vec3(0.1f, -0.2f, 0.3f), Vec3(1.f, 0.f, 0.f), c.length,
                           c.target + Vec3(0.1f, -0.2f, 0.3f)};
}

// Chi-square of 10^6 samples of a connection strategy in 200 bins of x = r / (1 + r) (which
// maps an infinite segment to [0, 1)), densities integrated per bin; and the pdf's integral.
void check_connection_chi2(const std::string& type) {
    auto strategy = make_connection(type);
    ASSERT_TRUE(strategy);
    const int cases = int(std::size(kConnectionCases));
    for (const ConnectionCase& c : kConnectionCases) {
        SCOPED_TRACE(c.name);
        const ConnectionQuery q = query_of(c);
        Chi2Options opt;
        opt.nx = 200;
        opt.ny = 1;
        opt.x0 = 0;
        opt.x1 = std::isfinite(c.length) ? c.length / (1 + c.length) : 1.0;
        opt.y0 = 0;
        opt.y1 = 1;
        opt.seed = seed_from_name(type + c.name);
        size_t outside = 0;
        auto sample = [&](Pcg32& rng) -> std::optional<std::pair<double, double>> {
            const double r = strategy->sample(q, rng.next_double());
            if (!(r >= 0 && r < c.length)) {
                ++outside;
                return std::nullopt;
            }
            return std::make_pair(r / (1 + r), 0.5);
        };
        auto pdf = [&](double x, double) {
            x = std::min(x, 1 - 1e-9);  // the quadrature touches x = 1 (r infinite)
            const double r = x / (1 - x);
            return strategy->pdf(q, r) / ((1 - x) * (1 - x));  // dr/dx = (1 + r)^2
        };
        const Chi2Result r = chi2_test(opt, sample, pdf);
        EXPECT_EQ(outside, 0u) << "samples outside [0, length)";
        EXPECT_TRUE(r.error.empty()) << r.describe();
        EXPECT_GT(r.p_value, corrected_significance(cases)) << r.describe();
        EXPECT_NEAR(r.pdf_integral, 1.0, 2e-4) << r.describe();
    }
}

}  // namespace

TEST(ConnectionSampling, LineToPointSamplesMatchTheirPdf) {
    check_connection_chi2("line_to_point");  // on the infinite segment: equiangular
}

TEST(ConnectionSampling, EquiangularSamplesMatchTheirPdf) { check_connection_chi2("equiangular"); }

TEST(ConnectionSampling, DeterministicPlacesNoVertex) {
    auto strategy = make_connection("deterministic");
    EXPECT_FALSE(strategy->places_vertex());
    EXPECT_TRUE(make_connection("line_to_point")->places_vertex());
    EXPECT_TRUE(make_connection("equiangular")->places_vertex());
}

// Fig. 5.7 (middle) as a test: with a light point at distance |l| from a segment's start, the
// length r + |x(r) - light| of the connection through the sampled vertex (its time, in a
// medium of any index) is uniform on [|l|, length + |x(length) - light|] under line-to-point
// sampling; equiangular sampling (radiance-driven) and uniform vertex positions are not.
TEST(ConnectionSampling, LineToPointConnectionTimesAreUniform) {
    const ConnectionCase c{"fig_5_7", Vec3(1.5f, 0.8f, 0.f), 6.0};
    const ConnectionQuery q = query_of(c);
    const Vec3 l = q.target - q.origin;
    auto time_of = [&](double r) {
        const Vec3 x = q.origin + q.direction * float(r);
        return r + double(length(q.target - x));
    };
    const double t_a = double(length(l)), t_b = time_of(c.length);
    constexpr int kBins = 20, kSamples = 200000;
    auto chi2_of = [&](auto&& sample) {
        std::vector<int> count(kBins, 0);
        Pcg32 rng(7, 11);
        for (int i = 0; i < kSamples; ++i) {
            const double t = time_of(sample(rng.next_double()));
            ++count[std::clamp(int((t - t_a) / (t_b - t_a) * kBins), 0, kBins - 1)];
        }
        double chi2 = 0;
        const double expected = double(kSamples) / kBins;
        for (int n : count) chi2 += (n - expected) * (n - expected) / expected;
        return chi2;  // 19 degrees of freedom: P(chi2 > 45) < 1e-3
    };
    auto line_to_point = make_connection("line_to_point");
    auto equiangular = make_connection("equiangular");
    EXPECT_LT(chi2_of([&](double u) { return line_to_point->sample(q, u); }), 45.0);
    EXPECT_GT(chi2_of([&](double u) { return equiangular->sample(q, u); }), 1000.0);
    EXPECT_GT(chi2_of([&](double u) { return u * c.length; }), 1000.0);
}

namespace {

struct AngularCase {
    const char* name;
    double r, L;  // distance to the next vertex, distance to the target
};
const AngularCase kAngularCases[] = {
    {"target_beyond", 0.5, 2.0},
    {"target_within", 3.0, 1.0},
    {"nearly_equal", 1.2, 1.0},
};

AngularQuery angular_query(const AngularCase& c, const PhaseFunction* phase) {
    AngularQuery q;
    q.position = Vec3(0.2f, -0.1f, 0.4f);
    q.wi = normalize(Vec3(0.3f, -0.5f, 0.8f));
    q.phase = phase;
    q.distance = c.r;
    q.has_target = true;
    q.target = q.position + normalize(Vec3(0.6f, 0.7f, -0.2f)) * float(c.L);
    return q;
}

}  // namespace

// Chi-square of time-angular directions over the sphere against their solid-angle pdf, and
// its integral; without a usable target the strategy is the phase function.
TEST(AngularSampling, TimeSamplesMatchTheirPdf) {
    auto strategy = make_angular("time");
    auto phase = make_phase_function("hg", 0.4);
    const int tests = int(std::size(kAngularCases)) + 1;
    auto run = [&](const std::string& name, const AngularQuery& q) {
        SCOPED_TRACE(name);
        Chi2Options opt;
        opt.seed = seed_from_name("time" + name);
        auto sample = [&](Pcg32& rng) -> std::optional<std::pair<double, double>> {
            const Vec3 w = strategy->sample(q, Vec2(rng.next_float(), rng.next_float()));
            return sphere_coords(w);
        };
        auto pdf = [&](double cos_theta, double phi) {
            return strategy->pdf(q, sphere_direction(cos_theta, phi));
        };
        const Chi2Result r = chi2_test(opt, sample, pdf);
        EXPECT_TRUE(r.error.empty()) << r.describe();
        EXPECT_EQ(r.histogrammed, r.samples);
        EXPECT_GT(r.p_value, corrected_significance(tests)) << r.describe();
        EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3) << r.describe();
    };
    for (const AngularCase& c : kAngularCases) run(c.name, angular_query(c, phase.get()));
    AngularQuery no_target = angular_query(kAngularCases[0], phase.get());
    no_target.has_target = false;
    run("no_target", no_target);
    EXPECT_TRUE(make_angular("phase")->steady());
    EXPECT_FALSE(strategy->steady());
}

// Fig. 5.7 (right) as a test: with the next distance r fixed, the length r + |x_next - target|
// (the time of the path to the target) is uniform on [r + |L - r|, 2 r + L] under time angular
// sampling, and not under isotropic phase sampling.
TEST(AngularSampling, TimeAngularPathTimesAreUniform) {
    auto iso = make_phase_function("isotropic");
    auto time = make_angular("time");
    auto phase = make_angular("phase");
    for (const AngularCase& c : kAngularCases) {
        SCOPED_TRACE(c.name);
        const AngularQuery q = angular_query(c, iso.get());
        const double t0 = c.r + std::abs(c.L - c.r), t1 = 2 * c.r + c.L;
        constexpr int kBins = 20, kSamples = 200000;
        auto chi2_of = [&](const AngularSampler& s) {
            std::vector<int> count(kBins, 0);
            Pcg32 rng(3, 9);
            for (int i = 0; i < kSamples; ++i) {
                const Vec3 w = s.sample(q, Vec2(rng.next_float(), rng.next_float()));
                const double t = c.r + double(length(q.position + w * float(c.r) - q.target));
                ++count[std::clamp(int((t - t0) / (t1 - t0) * kBins), 0, kBins - 1)];
            }
            double chi2 = 0;
            const double expected = double(kSamples) / kBins;
            for (int n : count) chi2 += (n - expected) * (n - expected) / expected;
            return chi2;
        };
        EXPECT_LT(chi2_of(*time), 45.0);     // 19 dof: P(chi2 > 45) < 1e-3
        EXPECT_GT(chi2_of(*phase), 1000.0);  // isotropic: the length's density grows linearly
    }
}

// ---------------------------------------------------------------------------------------------
// Unbiasedness of every combination

namespace {

// A foggy box: [-1, 1]^3 bounded by a null surface, holding an HG (g = 0.5) medium of albedo
// 0.8, a spherical area light and a diffuse sphere; the camera looks at it from outside.
// Paths leave the box for good, so a path of at most max_depth = 5 segments is shorter than
// the window's end (camera distance 3 + 6 box diagonals 3.47 < 24). The light is large and
// dim: estimates near a small bright light are dominated by rare vertices close to it, so a
// few thousand samples would not estimate their own variance (and a point light in a medium
// gives the steady estimators infinite variance).
// `media` replaces the box's homogeneous fog and may add shapes: see nested_media().
std::string foggy_box(const std::string& integrator, const std::string& film, int spp,
                      const std::string& media = "") {
    std::ostringstream s;
    s << "<scene version=\"3.0.0\">"
      << (media.empty() ? "<medium type=\"homogeneous\" id=\"fog\"><float name=\"sigma_s\" "
                          "value=\"0.8\"/><float name=\"sigma_a\" value=\"0.2\"/><phase "
                          "type=\"hg\"><float name=\"g\" value=\"0.5\"/></phase></medium>"
                        : media)
      << integrator
      << "<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/>"
         "<transform name=\"to_world\"><lookat origin=\"0.2,0.1,4\" target=\"0,0,0\" "
         "up=\"0,1,0\"/></transform><sampler type=\"independent\"><integer "
         "name=\"sample_count\" value=\""
      << spp << "\"/></sampler>" << film
      << "</sensor>"
         "<shape type=\"cube\"><bsdf type=\"null\"/><ref name=\"interior\" id=\"fog\"/></shape>"
         "<shape type=\"sphere\"><point name=\"center\" x=\"0.3\" y=\"0.35\" z=\"0.1\"/>"
         "<float name=\"radius\" value=\"0.35\"/><emitter type=\"area\"><rgb name=\"radiance\" "
         "value=\"1.5,1.2,1\"/></emitter></shape>"
         "<shape type=\"sphere\"><point name=\"center\" x=\"-0.4\" y=\"-0.35\" z=\"0\"/>"
         "<float name=\"radius\" value=\"0.3\"/><bsdf type=\"diffuse\"><float "
         "name=\"reflectance\" value=\"0.7\"/></bsdf></shape>"
         "</scene>";
    return s.str();
}

std::string transient_film(double start, double bin_width, int bins) {
    std::ostringstream s;
    s << "<film type=\"transient\"><integer name=\"width\" value=\"6\"/><integer "
         "name=\"height\" value=\"6\"/><float name=\"start\" value=\""
      << start << "\"/><float name=\"bin_width\" value=\"" << bin_width
      << "\"/><integer name=\"bins\" value=\"" << bins
      << "\"/><string name=\"aovs\" value=\"variance\"/><rfilter type=\"box\"/></film>";
    return s.str();
}

struct Combination {
    std::string distance, connection, angular;
    bool mis;
    std::string name() const {
        return distance + "/" + connection + "/" + angular + (mis ? "/mis" : "");
    }
    std::string integrator() const {
        return "<integrator type=\"transient_path\"><integer name=\"max_depth\" value=\"5\"/>"
               "<distance type=\"" +
               distance + "\">" +
               (distance == "exponential" ? "<float name=\"lambda\" value=\"0.6\"/>" : "") +
               "</distance><connection type=\"" + connection + "\"/><angular type=\"" + angular +
               "\"/><boolean name=\"mis\" value=\"" + (mis ? "true" : "false") +
               "\"/></integrator>";
    }
};

std::vector<Combination> all_combinations() {
    std::vector<Combination> out;
    for (const char* d : {"mean_free_path", "exponential"})
        for (const char* c : {"deterministic", "line_to_point", "equiangular"})
            for (const char* a : {"phase", "time"})
                for (bool mis : {false, true}) out.push_back({d, c, a, mis});
    return out;
}

// Compares a render with a reference of the same quantity (channel sums; the channels of one
// sample are correlated, so a sum's variance is taken as 3x the sum of the channels'
// variances, its Cauchy-Schwarz bound). Two statistics, each a sum of z^2 with z = difference
// / sqrt(var + var_ref), chi-square with as many degrees of freedom as terms when both renders
// are unbiased:
//  - cell by cell, over the cells the reference resolves to 10 % (a cell fed by a few rare,
//    large samples has a variance estimate too noisy for its z to be normal);
//  - per time bin, summed over all pixels (pixels are independent), for every bin with light.
// Each must stay below its 1e-4 upper quantile (Wilson-Hilferty), and every |z| below 5.
void expect_same(const test::Cube& a, const test::Cube& va, const test::Cube& ref,
                 const test::Cube& vref, const std::string& what) {
    ASSERT_EQ(a.data.size(), ref.data.size());
    auto chi2_bound = [](int n) {
        const double k = 2.0 / (9.0 * n);
        return n * std::pow(1 - k + 3.72 * std::sqrt(k), 3);  // z = 3.72: P = 1e-4
    };
    double chi2 = 0, worst = 0;
    int n = 0;
    std::vector<double> bin_a(size_t(a.T), 0.0), bin_ref(size_t(a.T), 0.0),
        bin_var(size_t(a.T), 0.0);
    for (int y = 0; y < a.H; ++y)
        for (int x = 0; x < a.W; ++x)
            for (int t = 0; t < a.T; ++t) {
                const double var = 3 * (va.energy(y, x, t) + vref.energy(y, x, t));
                bin_a[size_t(t)] += a.energy(y, x, t);
                bin_ref[size_t(t)] += ref.energy(y, x, t);
                bin_var[size_t(t)] += var;
                const double r = ref.energy(y, x, t);
                if (!(var > 0) || !(std::sqrt(3 * vref.energy(y, x, t)) < 0.1 * r)) continue;
                const double z = (a.energy(y, x, t) - r) / std::sqrt(var);
                chi2 += z * z;
                worst = std::max(worst, std::abs(z));
                ++n;
            }
    ASSERT_GT(n, a.H * a.W / 2) << what;  // most pixels have a resolved cell
    EXPECT_LT(chi2, chi2_bound(n)) << what << ": " << n << " cells";
    double bin_chi2 = 0;
    int bins = 0;
    for (size_t t = 0; t < bin_a.size(); ++t) {
        if (!(bin_var[t] > 0)) continue;
        const double z = (bin_a[t] - bin_ref[t]) / std::sqrt(bin_var[t]);
        bin_chi2 += z * z;
        worst = std::max(worst, std::abs(z));
        ++bins;
    }
    EXPECT_LT(bin_chi2, chi2_bound(bins)) << what << ": " << bins << " bins";
    EXPECT_LT(worst, 5.0) << what;
}

}  // namespace

TEST(TimeStrategies, EveryCombinationRendersTheSameCube) {
    // Reference: the steady strategies with 4x the samples.
    const std::string film = transient_film(3.0, 1.0, 14);  // [3, 17)
    const Combination steady{"mean_free_path", "deterministic", "phase", false};
    auto ref_scene = load_scene_string(foggy_box(steady.integrator(), film, 8192));
    const auto [ref, ref_var] = test::render_cube_and_variance(*ref_scene, 1, "strategies-ref");
    for (const Combination& c : all_combinations()) {
        SCOPED_TRACE(c.name());
        auto scene = load_scene_string(foggy_box(c.integrator(), film, 2048));
        const auto [cube, var] = test::render_cube_and_variance(*scene, 2, "strategies");
        expect_same(cube, var, ref, ref_var, c.name());
    }
}

TEST(TimeStrategies, EveryCombinationSumsToTheSteadyRender) {
    // One bin holding the whole window: the time integral of each combination, against the
    // steady `path` integrator (mean free path, shadow rays, phase sampling).
    const std::string film = transient_film(0.0, 24.5, 1);
    auto ref_scene = load_scene_string(foggy_box(
        "<integrator type=\"path\"><integer name=\"max_depth\" value=\"5\"/></integrator>", film,
        2048));
    const auto [ref, ref_var] = test::render_cube_and_variance(*ref_scene, 3, "steady-ref");
    for (const Combination& c : all_combinations()) {
        SCOPED_TRACE(c.name());
        auto scene = load_scene_string(foggy_box(c.integrator(), film, 2048));
        const auto [cube, var] = test::render_cube_and_variance(*scene, 4, "steady");
        expect_same(cube, var, ref, ref_var, c.name());
    }
}

namespace {

// The box's medium becomes a heterogeneous grid (a 4^3 .vol of densities 0.2-1.6, HG g 0.3:
// majorant sampling, ratio tracking, null collisions), and a sphere of radius 0.4 bounded by a
// null surface holds a homogeneous medium of index 1.33 inside it (paths and shadow rays cross
// between two media, and time runs at c / 1.33 in one of them).
std::string nested_media(const std::string& vol_path) {
    return "<medium type=\"heterogeneous\" id=\"fog\"><string name=\"density\" value=\"" +
           vol_path +
           "\"/><float name=\"albedo\" value=\"0.8\"/><phase type=\"hg\"><float name=\"g\" "
           "value=\"0.3\"/></phase></medium>"
           "<medium type=\"homogeneous\" id=\"water\"><float name=\"sigma_s\" value=\"0.6\"/>"
           "<float name=\"sigma_a\" value=\"0.1\"/><float name=\"eta\" value=\"1.33\"/></medium>"
           "<shape type=\"sphere\"><point name=\"center\" x=\"0.2\" y=\"-0.4\" z=\"0.3\"/>"
           "<float name=\"radius\" value=\"0.4\"/><bsdf type=\"null\"/><ref name=\"interior\" "
           "id=\"water\"/><ref name=\"exterior\" id=\"fog\"/></shape>";
}

// A 4^3 grid over the box [-1, 1]^3 with densities 0.2-1.6 in a fixed scramble.
void write_density_grid(const std::string& path) {
    const auto grid = test::make_grid(4, 4, 4, Vec3(-1.f), Vec3(1.f), [](int x, int y, int z) {
        const int i = (z * 4 + y) * 4 + x;
        return 0.2 + 1.4 * double((i * 37) % 64) / 63.0;
    });
    test::write_bytes(path, grid.bytes());
}

}  // namespace

// The same unbiasedness test where the distance strategies meet a heterogeneous medium and a
// nested medium of another index: the time strategies and their MIS with the steady ones.
TEST(TimeStrategies, EveryCombinationInHeterogeneousAndNestedMedia) {
    const auto dir = femto::test::temp_dir("strategies-media");
    const std::string vol = (dir / "density.vol").string();
    write_density_grid(vol);
    const std::string media = nested_media(vol);
    const std::string film = transient_film(3.0, 1.0, 14);
    const Combination steady{"mean_free_path", "deterministic", "phase", false};
    auto ref_scene = load_scene_string(foggy_box(steady.integrator(), film, 8192, media));
    const auto [ref, ref_var] = test::render_cube_and_variance(*ref_scene, 5, "media-ref");
    for (const Combination& c : all_combinations()) {
        if (c.connection == "deterministic" && c.angular == "phase") continue;  // distance only
        SCOPED_TRACE(c.name());
        auto scene = load_scene_string(foggy_box(c.integrator(), film, 2048, media));
        const auto [cube, var] = test::render_cube_and_variance(*scene, 6, "media");
        expect_same(cube, var, ref, ref_var, c.name());
    }
    std::filesystem::remove_all(dir);
}

// Misplaced or repeated strategies are scene errors naming the tag and its line.
TEST(TimeStrategies, BadStrategiesAreLocatedSceneErrors) {
    auto error_of = [](const std::string& strategies) {
        return test::load_error(test::scene_xml("<integrator type=\"transient_path\">\n" +
                                                strategies +
                                                "\n</integrator><emitter type=\"point\"/>"));
    };
    const std::string twice =
        error_of("<connection type=\"line_to_point\"/><connection type=\"equiangular\"/>");
    EXPECT_NE(twice.find("at most one <connection>"), std::string::npos) << twice;
    EXPECT_NE(twice.find(":4:"), std::string::npos) << twice;  // the second <connection>
    const std::string two_angular = error_of("<angular type=\"time\"/><angular type=\"phase\"/>");
    EXPECT_NE(two_angular.find("at most one <angular>"), std::string::npos) << two_angular;
    // An angular plugin under <connection>, and a name that is no plugin at all.
    const std::string wrong_kind = error_of("<connection type=\"time\"/>");
    EXPECT_NE(wrong_kind.find("time"), std::string::npos) << wrong_kind;
    EXPECT_NE(wrong_kind.find(":4:"), std::string::npos) << wrong_kind;
    const std::string unknown = error_of("<angular type=\"uniform\"/>");
    EXPECT_NE(unknown.find("uniform"), std::string::npos) << unknown;
    EXPECT_NE(unknown.find(":4:"), std::string::npos) << unknown;
}
