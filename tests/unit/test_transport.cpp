// The transport toolkit's pieces on their own (femto/mis.h, femto/path_clock.h,
// femto/transport.h): MIS weights, the path clock's time rules, the throughput's colour
// transfers, medium tracking, the distance mixture's density and the connection reach.
#include <gtest/gtest.h>

#include <cmath>

#include "chi2.h"
#include "femto/host.h"
#include "femto/mis.h"
#include "femto/path_clock.h"
#include "femto/random.h"
#include "femto/transport.h"
#include "scene_util.h"

using namespace femto;

namespace {

// A point light at (0, 0, 2) with a Gaussian pulse, a rectangle below, a transient film of
// window [1, 3).
std::unique_ptr<Scene> small_scene(const std::string& pulse = "") {
    return load_scene_string(test::scene_xml(
        "<sensor type=\"perspective\"><film type=\"transient\"><integer name=\"width\" "
        "value=\"4\"/><integer name=\"height\" value=\"4\"/><float name=\"start\" value=\"1\"/>"
        "<float name=\"bin_width\" value=\"0.5\"/><integer name=\"bins\" value=\"4\"/></film>"
        "</sensor><shape type=\"rectangle\"/><emitter type=\"point\"><point name=\"position\" "
        "value=\"0,0,2\"/>" +
        pulse + "</emitter>"));
}

}  // namespace

TEST(Mis, HeuristicsSumToOne) {
    for (float a : {0.f, 0.3f, 1.f, 7.f})
        for (float b : {0.1f, 2.f, 50.f}) {
            EXPECT_NEAR(power_heuristic(a, b) + power_heuristic(b, a), 1.f, 1e-6f);
            EXPECT_NEAR(balance_heuristic(a, b) + balance_heuristic(b, a), 1.0, 1e-12);
            // n samples of a technique weigh as one sample of n times its density
            EXPECT_FLOAT_EQ(power_heuristic(3.f, a, 2.f, b), power_heuristic(3 * a, 2 * b));
        }
    EXPECT_EQ(power_heuristic(0.f, 0.f), 0.f);
    EXPECT_EQ(balance_heuristic(0.0, 0.0), 0.0);
    EXPECT_FLOAT_EQ(power_heuristic(1.f, 1.f), 0.5f);
    EXPECT_DOUBLE_EQ(balance_heuristic(1.0, 3.0), 0.25);
}

TEST(PathClock, TimeIsOpticalLengthPlusDelays) {
    auto scene = small_scene();
    ContributionList out;
    PathClock clock(*scene, out, Vec3(1.f, 0.f, 0.f));
    EXPECT_EQ(clock.time(), 0.0);
    clock.travel_to(Vec3(1.f, 0.f, 2.f), 1.0);
    clock.travel_to(Vec3(1.f, 0.f, 1.f), 1.5);  // inside glass: eta * d
    clock.delay(0.25);
    EXPECT_DOUBLE_EQ(clock.time(), 3.75);
    EXPECT_EQ(clock.position().z, 1.f);
}

TEST(PathClock, TheFirstScatteringVertexSetsTheSensorDistance) {
    auto scene = small_scene();
    ContributionList out;
    PathClock clock(*scene, out, Vec3(0.f));
    clock.travel_to(Vec3(0.f, 1.25f, 0.f), 1.0);
    clock.reach_vertex();
    clock.travel_to(Vec3(0.f, 1.25f, 3.f), 1.0);
    clock.reach_vertex();  // later vertices do not move it
    EXPECT_DOUBLE_EQ(out.sensor_distance(), 1.25);
}

TEST(PathClock, WindowCutAndEmissionTime) {
    // The film records up to t = 3; the pulse cannot start before its earliest time, so a
    // path may travel 3 - earliest before nothing it carries arrives in time.
    auto scene = small_scene(
        "<string name=\"pulse\" value=\"box\"/><float name=\"pulse_width\" value=\"0.5\"/>"
        "<float name=\"time_offset\" value=\"0.2\"/>");
    const TimeWindow& w = scene->time_window();
    EXPECT_DOUBLE_EQ(w.end, 3.0);
    const double earliest = scene->earliest_emission();
    EXPECT_DOUBLE_EQ(w.path_cut(), 3.0 - earliest);
    ContributionList out;
    PathClock clock(*scene, out, Vec3(0.f));
    clock.delay(w.path_cut());
    EXPECT_FALSE(clock.expired());
    EXPECT_DOUBLE_EQ(clock.remaining(), 0.0);
    clock.delay(1e-9);
    EXPECT_TRUE(clock.expired());
    // Recorded light arrives at the path's time + the connection + the emission time, which
    // lies in the pulse's support.
    auto sampler = create_default_object(PluginKind::Sampler, "independent", {});
    Sampler& s = static_cast<Sampler&>(*sampler);
    s.start(1, 0, 0);
    ContributionList list;
    PathClock c2(*scene, list, Vec3(0.f));
    c2.travel_to(Vec3(0.f, 0.f, 1.f), 1.0);
    for (int i = 0; i < 100; ++i) c2.record(Color(1.f), *scene->emitters()[0], s, 0.5);
    ASSERT_EQ(list.items().size(), 100u);
    for (const Contribution& c : list.items()) {
        EXPECT_GE(c.time, 1.5 + earliest - 1e-12);
        EXPECT_LE(c.time, 1.5 + earliest + 0.5 + 1e-12);
    }
}

TEST(PathClock, ADeltaPulseDrawsNoNumber) {
    auto scene = small_scene();
    auto a = create_default_object(PluginKind::Sampler, "independent", {});
    auto b = create_default_object(PluginKind::Sampler, "independent", {});
    Sampler &sa = static_cast<Sampler&>(*a), &sb = static_cast<Sampler&>(*b);
    sa.start(3, 1, 2), sb.start(3, 1, 2);
    ContributionList out;
    PathClock clock(*scene, out, Vec3(0.f));
    clock.record(Color(1.f), *scene->emitters()[0], sa, 2.0);
    EXPECT_EQ(sa.next_1d(), sb.next_1d());
    ASSERT_EQ(out.items().size(), 1u);
    EXPECT_DOUBLE_EQ(out.items()[0].time, 2.0);
}

TEST(Throughput, DiagonalTransfersStayPerChannelAndMatricesMixChannels) {
    Throughput t;
    t *= Color(0.5f, 1.f, 2.f);
    ColorMatrix diag;
    diag.m[0][0] = 2, diag.m[1][1] = 0.5f, diag.m[2][2] = 1;
    t.transfer(diag);
    const Color c = t(Color(1.f));
    EXPECT_FLOAT_EQ(c.r, 1.f);
    EXPECT_FLOAT_EQ(c.g, 0.5f);
    EXPECT_FLOAT_EQ(c.b, 2.f);
    EXPECT_FLOAT_EQ(t.max_gain(), 2.f);
    // Fluorescence-like: blue arriving leaves as green.
    ColorMatrix blue_to_green;
    blue_to_green.m[0][0] = blue_to_green.m[1][1] = blue_to_green.m[2][2] = 0;
    blue_to_green.m[1][2] = 1;
    t.transfer(blue_to_green);
    t *= Color(3.f);  // a later BSDF weight (applies to the light arriving)
    const Color g = t(Color(0.f, 0.f, 1.f));
    EXPECT_FLOAT_EQ(g.r, 0.f);
    EXPECT_FLOAT_EQ(g.g, 0.5f * 3.f);  // camera-side weight of green times the incoming blue
    EXPECT_FLOAT_EQ(g.b, 0.f);
    EXPECT_FLOAT_EQ(t.max_gain(), 1.5f);
}

TEST(MediumTracker, RefractionChangesTheIndexOutsideMedia) {
    MediumTracker m;
    EXPECT_DOUBLE_EQ(m.eta(), 1.0);
    BsdfSample into;
    into.sampled_lobe = kBsdfDeltaTransmission;
    into.eta = 1.5f;
    m.refract(into);
    EXPECT_DOUBLE_EQ(m.eta(), 1.5);
    BsdfSample reflect;
    reflect.sampled_lobe = kBsdfDeltaReflection;
    reflect.eta = 1.f;
    m.refract(reflect);
    EXPECT_DOUBLE_EQ(m.eta(), 1.5);
}

TEST(DistanceMixture, DensityIntegratesToOneAndMatchesSurvival) {
    auto medium_obj = create_default_object(PluginKind::Medium, "homogeneous", {});
    const Medium& medium = static_cast<const Medium&>(*medium_obj);
    auto exp_obj = create_default_object(PluginKind::Distance, "exponential", {});
    const auto& exponential = static_cast<const DistanceSampler&>(*exp_obj);
    const DistanceContext ctx{4.0};
    for (const bool mis : {false, true}) {
        SCOPED_TRACE(mis ? "mixture" : "strategy alone");
        const DistanceMixture mix(medium, &exponential, mis, ctx);
        // P(r > d) = 1 - integral_0^d pdf
        const double d = 1.7, steps = 20000, h = d / steps;
        double integral = 0;
        for (int i = 0; i < steps; ++i) integral += mix.pdf((i + 0.5) * h) * h;
        EXPECT_NEAR(integral + mix.survival(d), 1.0, 1e-7);
        // Samples follow the density: a chi-square test over 20 equal-probability cells of
        // the cdf 1 - survival.
        Pcg32 rng(11, mis ? 2 : 1);
        std::vector<double> counts(20, 0.0);
        const int n = 100000;
        for (int i = 0; i < n; ++i) {
            const double r = mix.sample(rng.next_double());
            const double cdf = 1 - mix.survival(r);
            counts[std::min(19, int(cdf * 20))] += 1;
        }
        double chi2 = 0;
        for (double c : counts) chi2 += (c - n / 20.0) * (c - n / 20.0) / (n / 20.0);
        EXPECT_LT(chi2, 43.8);  // 19 dof, p = 1e-3
    }
}

// The cache gives the mixture a fresh DistanceMixture of the medium asked for would be, and
// a new one whenever the medium changes (media alternating, as at a path's boundaries).
TEST(DistanceMixtureCache, GivesTheMixtureOfTheMediumAskedFor) {
    auto medium_of = [](double sigma_t) {
        Properties props("homogeneous", {});
        props.set_float("sigma_t", sigma_t);
        return create_child_object(PluginKind::Medium, "homogeneous", props);
    };
    const auto thin_obj = medium_of(0.5), dense_obj = medium_of(4.0);
    const Medium& thin = static_cast<const Medium&>(*thin_obj);
    const Medium& dense = static_cast<const Medium&>(*dense_obj);
    auto exp_obj = create_default_object(PluginKind::Distance, "exponential", {});
    const auto& exponential = static_cast<const DistanceSampler&>(*exp_obj);
    const DistanceContext ctx{4.0};
    DistanceMixtureCache cache(&exponential, true, ctx);
    DistanceMixtureCache free_paths;  // mean free paths alone
    for (const Medium* m : {&thin, &thin, &dense, &thin, &dense, &dense}) {
        const DistanceMixture fresh(*m, &exponential, true, ctx);
        const DistanceMixture fresh_free(*m, nullptr, false, DistanceContext{kInfinity});
        for (const double d : {0.1, 0.7, 2.5}) {
            EXPECT_EQ(cache(*m).at(d).pdf, fresh.at(d).pdf);
            EXPECT_EQ(cache(*m).at(d).survival, fresh.at(d).survival);
            EXPECT_EQ(free_paths(*m).at(d).pdf, fresh_free.at(d).pdf);
        }
        EXPECT_EQ(free_paths(*m).steady_rate(), DistanceSampler::mean_free_path_rate(*m));
    }
    EXPECT_EQ(free_paths(thin).steady_rate(), 0.5);
    EXPECT_EQ(free_paths(dense).steady_rate(), 4.0);
}

TEST(DistanceMixture, SurvivalIsTheTransmittanceOnlyWhereItIs) {
    // Mean-free-path distances in a grey homogeneous medium survive with exactly the medium's
    // transmittance, and a shadow connection's segment densities hand it over
    // (SegmentDensities::piece()); with another rate, or another extinction per channel, they
    // leave the medium to compute it.
    auto medium_with = [](const Color& sigma_t) {
        Properties props("homogeneous", {});
        props.set_color("sigma_t", sigma_t);
        return create_child_object(PluginKind::Medium, "homogeneous", props);
    };
    const auto grey_obj = medium_with(Color(1.7f)), coloured_obj = medium_with(Color(0.5f, 1, 2));
    const Medium& grey = static_cast<const Medium&>(*grey_obj);
    const Medium& coloured = static_cast<const Medium&>(*coloured_obj);
    auto exp_obj = create_default_object(PluginKind::Distance, "exponential", {});
    const auto& exponential = static_cast<const DistanceSampler&>(*exp_obj);
    const DistanceContext window{4.0};
    auto sampler = create_default_object(PluginKind::Sampler, "independent", {});
    Sampler& s = static_cast<Sampler&>(*sampler);
    s.start(1, 0, 0);
    const Ray ray{Vec3(0.f), Vec3(0.f, 0.f, 1.f), 0.f, kInfinity};
    EXPECT_TRUE(DistanceMixture(grey, nullptr, false, window).survival_is_transmittance());
    EXPECT_FALSE(DistanceMixture(grey, &exponential, true, window).survival_is_transmittance());
    EXPECT_FALSE(DistanceMixture(coloured, nullptr, false, window).survival_is_transmittance());
    SegmentDensities segment(nullptr, false, window);
    for (const double d : {0.05, 0.7, 2.5, 9.0}) {
        const std::optional<Color> known = segment.piece(&grey, d);
        ASSERT_TRUE(known.has_value());
        const Color exact = grey.transmittance(ray, d, s);
        for (int c = 0; c < 3; ++c) EXPECT_EQ((*known)[c], exact[c]) << d;
        EXPECT_FALSE(segment.piece(&coloured, d).has_value());
        EXPECT_FALSE(segment.piece(nullptr, d).has_value());
    }
    // sample_distance() takes the same shortcut: its weight is what the medium's own
    // transmittance gives, a vertex's (u = 0.1, 0.5) and the surface's at 0.8 (u = 0.9).
    const DistanceMixture free_paths(grey, nullptr, false, window);
    for (const double u : {0.1, 0.5, 0.9}) {
        const DistanceSample ds = sample_distance(grey, ray, 0.8, free_paths, u, s);
        EXPECT_EQ(ds.scattered, u < 0.6) << u;
        const double d = ds.scattered ? ds.distance : 0.8;
        const Color tr = grey.transmittance(ray, d, s);
        const Color expected = ds.scattered
                                   ? tr * grey.sigma_s(ray.at(float(d))) * float(1.0 / ds.pdf)
                                   : tr * float(1.0 / free_paths.survival(d));
        for (int c = 0; c < 3; ++c) EXPECT_EQ(ds.weight[c], expected[c]) << u;
    }
}

TEST(ConnectionReach, AVertexAtTheReachArrivesExactlyAtTheWindow) {
    // eta r + |x(r) - target| = remaining at the reach, and less before it.
    const Vec3 o(0.f, 0.f, 0.f), d(1.f, 0.f, 0.f), target(2.f, 1.f, 0.f);
    for (const double eta : {1.0, 1.33})
        for (const double remaining : {2.5, 4.0, 10.0}) {
            const double r = connection_reach(o, d, target, eta, remaining);
            const double arrive = eta * r + std::hypot(2.0 - r, 1.0);
            EXPECT_NEAR(arrive, remaining, 1e-9 * remaining) << eta << " " << remaining;
        }
    EXPECT_EQ(connection_reach(o, d, target, 1.0, 2.0), 0.0);  // |target| > remaining
    EXPECT_TRUE(std::isinf(connection_reach(o, d, target, 1.0, kInfinity)));
}

TEST(SegmentDensities, PiecesSeenFromEitherEnd) {
    SegmentDensities none(nullptr, false, DistanceContext{});
    EXPECT_EQ(none.forward(true), 1.0);
    EXPECT_EQ(none.backward(false), 1.0);
    SegmentDensities one = none;
    one.add(0.5, 0.7);
    EXPECT_EQ(one.forward(true), 0.7);
    EXPECT_EQ(one.backward(true), 0.7);
    EXPECT_EQ(one.forward(false), 0.5);
    EXPECT_TRUE(one.single_medium());
    SegmentDensities with_vacuum = one;
    with_vacuum.add_vacuum();
    EXPECT_FALSE(with_vacuum.single_medium());
    EXPECT_EQ(with_vacuum.forward(true), 0.7);  // vacuum is passed surely
    SegmentDensities three = none;
    three.add(0.5, 0.7);
    three.add(0.25, 0.3);
    three.add(0.125, 0.2);
    EXPECT_DOUBLE_EQ(three.forward(true), 0.5 * 0.25 * 0.2);
    EXPECT_DOUBLE_EQ(three.backward(true), 0.125 * 0.25 * 0.7);
    EXPECT_DOUBLE_EQ(three.forward(false), 0.5 * 0.25 * 0.125);
    EXPECT_DOUBLE_EQ(three.backward(false), 0.5 * 0.25 * 0.125);
    three.clear();
    EXPECT_EQ(three.forward(true), 1.0);
}

TEST(SegmentDensities, MatchAWalkThatRestartsAtEachBoundary) {
    // Two media pieces (rates 1.3 over 0.7, then 0.4 over 1.1), sampled as a walk does: an
    // exponential in each piece, restarted at the boundary. The fraction passing both and the
    // histogram of stops in the second piece match forward(false) and forward(true).
    const double a = 0.7, b = 1.1, la = 1.3, lb = 0.4;
    Pcg32 rng(7, 1);
    constexpr int kN = 400000, kBins = 11;
    int passed = 0;
    std::vector<double> counts(kBins, 0.0);
    for (int i = 0; i < kN; ++i) {
        if (DistanceSampler::sample(la, rng.next_double()) < a) continue;
        const double r = DistanceSampler::sample(lb, rng.next_double());
        if (r >= b) {
            ++passed;
        } else {
            counts[size_t(r / b * kBins)] += 1;
        }
    }
    const auto densities = [&](double r) {
        SegmentDensities seg(nullptr, false, DistanceContext{});
        seg.add(DistanceSampler::survival(la, a), DistanceSampler::pdf(la, a));
        seg.add(DistanceSampler::survival(lb, r), DistanceSampler::pdf(lb, r));
        return seg;
    };
    const double p_pass = densities(b).forward(false);
    EXPECT_NEAR(passed / double(kN), p_pass, 4 * std::sqrt(p_pass * (1 - p_pass) / kN));
    double chi2 = 0;
    for (int k = 0; k < kBins; ++k) {
        const double r0 = b * k / kBins, r1 = b * (k + 1) / kBins;
        // Expected count: the density integrated over the bin (Simpson, exact to 1e-7 here).
        const double p =
            (r1 - r0) / 6 *
            (densities(r0).forward(true) + 4 * densities(0.5 * (r0 + r1)).forward(true) +
             densities(r1).forward(true));
        chi2 += (counts[size_t(k)] - kN * p) * (counts[size_t(k)] - kN * p) / (kN * p);
    }
    EXPECT_LT(chi2, 31.3);  // 10 dof, p = 5e-4
}

TEST(ShadowConnection, ThroughANullBoundedSlab) {
    // A slab 0.5 thick (z in [-0.25, 0.25]) of sigma_t 2 and index 1.5 behind null boundaries:
    // a connection from z = -3 to z = 3 keeps e^(-2 * 0.5) of the light and takes
    // 5.5 + 1.5 * 0.5 of optical length.
    auto scene = load_scene_string(test::scene_xml(
        "<medium type=\"homogeneous\" id=\"slab\"><float name=\"sigma_t\" value=\"2\"/><float "
        "name=\"albedo\" value=\"0\"/><float name=\"eta\" value=\"1.5\"/></medium><shape "
        "type=\"cube\"><transform name=\"to_world\"><scale x=\"5\" y=\"5\" z=\"0.25\"/>"
        "</transform><bsdf type=\"null\"/><ref name=\"interior\" id=\"slab\"/></shape>"));
    auto sampler = create_default_object(PluginKind::Sampler, "independent", {});
    Sampler& s = static_cast<Sampler&>(*sampler);
    s.start(1, 0, 0);
    EmitterSample light;
    light.p = Vec3(0.f, 0.f, 3.f);
    light.wi = Vec3(0.f, 0.f, 1.f);
    light.distance = 6.f;
    const ShadowConnection c =
        connect_to_light(*scene, Vec3(0.f, 0.f, -3.f), light, MediumTracker{}, s);
    // The optical length is measured between the actual points (the shadow ray restarts off
    // each boundary and stops short of the light), so it is exact to float rounding. The
    // transmittance follows the rays, which miss 2 offsets of 64 ulps of the slab's size
    // (docs/precision.md) and stop 1e-4 of the distance short of the light (outside the slab).
    EXPECT_NEAR(c.transmittance.r, std::exp(-1.0),
                std::exp(-1.0) * 2 * 2 * 5 * kRayOffsetScale + 1e-6);
    EXPECT_NEAR(c.optical_length, 5.5 + 1.5 * 0.5, 1e-6);
    // The connection reports its one medium piece: mean-free-path sampling (sigma_t 2) passes
    // the slab with probability e^(-1) and stops at its far side with density 2 e^(-1).
    SegmentDensities segment(nullptr, false, DistanceContext{});
    const ShadowConnection reported =
        connect_to_light(*scene, Vec3(0.f, 0.f, -3.f), light, MediumTracker{}, s, &segment);
    // The pieces' survival stood in for the slab's transmittance: the same, bit for bit.
    EXPECT_EQ(reported.transmittance.r, c.transmittance.r);
    EXPECT_EQ(reported.optical_length, c.optical_length);
    EXPECT_NEAR(segment.forward(false), std::exp(-1.0), 1e-5);
    EXPECT_NEAR(segment.forward(true), 2 * std::exp(-1.0), 1e-5);
    EXPECT_NEAR(segment.backward(true), 2 * std::exp(-1.0), 1e-5);
    EXPECT_FALSE(segment.single_medium());  // vacuum, the slab, vacuum
    // Blocked by an opaque surface.
    auto wall = load_scene_string(
        test::scene_xml("<shape type=\"rectangle\"><transform name=\"to_world\"><scale "
                        "value=\"5\"/></transform></shape>"));
    EXPECT_TRUE(connect_to_light(*wall, Vec3(0.f, 0.f, -3.f), light, MediumTracker{}, s).blocked());
}
