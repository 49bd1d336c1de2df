// Agreement of two integrators on the shipped scenes (tests of transient_light and
// transient_bdpt against transient_path): per-cell means over independent renders, a
// chi-square whose tolerance comes from the variances of those means.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "cube_util.h"
#include "femto/bsdf.h"
#include "femto/host.h"
#include "femto/sensor.h"
#include "scene_util.h"

namespace femto::test {

inline const std::string kScenes = std::string(FEMTO_SOURCE_DIR) + "/scenes/";

inline std::string read_text(const std::string& path) {
    std::ifstream in(path);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// The text of a shipped scene, to be changed and loaded from a string, with each file it
// includes written in place (the children of its <scene>), as one self-contained text.
inline std::string shipped_scene_text(const std::string& scene) {
    std::string xml = read_text(kScenes + scene + "/scene.xml");
    const std::string open = "<include filename=\"";
    for (size_t at = xml.find(open); at != std::string::npos; at = xml.find(open, at)) {
        const size_t name_end = xml.find('"', at + open.size());
        const size_t end = xml.find("/>", name_end) + 2;
        std::string file = xml.substr(at + open.size(), name_end - at - open.size());
        // A $name in the file name takes the scene's <default> (-D values do not reach here).
        for (size_t d = file.find('$'); d != std::string::npos; d = file.find('$')) {
            const size_t e = file.find_first_of(".-/", d);
            const std::string key =
                "<default name=\"" + file.substr(d + 1, e - d - 1) + "\" value=\"";
            const size_t v = xml.find(key) + key.size();
            file.replace(d, e - d, xml.substr(v, xml.find('"', v) - v));
        }
        const std::string text = read_text(kScenes + scene + "/" + file);
        const size_t body = text.find('>', text.find("<scene")) + 1;
        xml.replace(at, end - at, text.substr(body, text.rfind("</scene>") - body));
    }
    return xml;
}

// Replaces the first element from `open` up to and including `close`.
inline std::string replace_element(const std::string& xml, const std::string& open,
                                   const std::string& close, const std::string& with) {
    const size_t a = xml.find(open);
    const size_t b = a == std::string::npos ? a : xml.find(close, a);
    EXPECT_NE(b, std::string::npos) << open;
    if (b == std::string::npos) return xml;
    return xml.substr(0, a) + with + xml.substr(b + close.size());
}

// A shipped scene with its <integrator> replaced.
inline std::string with_integrator(const std::string& scene, const std::string& type, int max_depth,
                                   bool hide_emitters, const std::string& children = "") {
    std::string integrator = "<integrator type=\"" + type + "\">" + children;
    if (max_depth != 0)
        integrator += "<integer name=\"max_depth\" value=\"" + std::to_string(max_depth) + "\"/>";
    if (hide_emitters) integrator += "<boolean name=\"hide_emitters\" value=\"true\"/>";
    integrator += "</integrator>";
    std::string xml = shipped_scene_text(scene);
    xml = replace_element(xml, "<integrator", "</integrator>", integrator);
    if (scene == "tof-plane")  // the same view through a pinhole: [-2, 2]^2 at distance 5
        xml = replace_element(xml, "<sensor type=\"orthographic\">", "</transform>",
                              "<sensor type=\"perspective\"><float name=\"fov\" "
                              "value=\"43.60281897270362\"/><transform name=\"to_world\">"
                              "<lookat origin=\"0, 0, 5\" target=\"0, 0, 0\" up=\"0, 1, 0\"/>"
                              "</transform>");
    return xml;
}

// Per-cell means over independent renders and the variance of each mean. A cell sums the
// energy of `block` x `block` pixels and `group` consecutive bins.
struct Cells {
    int count = 0;
    std::vector<double> mean, var;
};

// Which pixels a light tracer can render: those whose camera rays (16 per pixel) all meet a
// surface with a non-delta BSDF first, or nothing. Light paths reach the camera only by a
// connection from a non-delta vertex, so pixels that see a mirror or glass directly are dark
// in a light tracer (BDPT covers them).
inline std::vector<bool> seen_through_connections(const Scene& scene) {
    const Film& film = scene.sensor().film();
    std::vector<bool> ok(size_t(film.width()) * size_t(film.height()), true);
    for (int y = 0; y < film.height(); ++y)
        for (int x = 0; x < film.width(); ++x)
            for (int j = 0; j < 16; ++j) {
                const Vec2 pos{float(x) + (float(j % 4) + 0.5f) / 4,
                               float(y) + (float(j / 4) + 0.5f) / 4};
                Ray ray = scene.sensor().sample_ray(pos, {0.5f, 0.5f});
                Hit hit;
                bool found = scene.intersect(ray, hit);
                while (found && hit.shape->bsdf()->is_null()) {
                    const float left = ray.tmax - hit.t;
                    ray = hit.spawn(ray.d);
                    ray.tmax = left;
                    found = scene.intersect(ray, hit);
                }
                if (found && hit.shape->bsdf()->has_delta_only())
                    ok[size_t(y) * size_t(film.width()) + size_t(x)] = false;
            }
    return ok;
}

// Cells hold the pixels `mask` allows (empty: all).
inline Cells cells_of(const std::vector<Cube>& runs, int block, int group,
                      const std::vector<bool>& mask = {}) {
    const Cube& c0 = runs[0];
    const int bx = c0.W / block, by = c0.H / block, groups = c0.T / group;
    Cells out;
    out.count = bx * by * groups;
    std::vector<double> s(size_t(out.count), 0.0), s2(size_t(out.count), 0.0);
    for (const Cube& c : runs) {
        std::vector<double> v(size_t(out.count), 0.0);
        for (int y = 0; y < by * block; ++y)
            for (int x = 0; x < bx * block; ++x) {
                if (!mask.empty() && !mask[size_t(y) * size_t(c.W) + size_t(x)]) continue;
                for (int t = 0; t < groups * group; ++t)
                    v[size_t(((y / block) * bx + x / block) * groups + t / group)] +=
                        c.energy(y, x, t);
            }
        for (size_t i = 0; i < v.size(); ++i) s[i] += v[i], s2[i] += v[i] * v[i];
    }
    const double k = double(runs.size());
    out.mean.resize(s.size());
    out.var.resize(s.size());
    for (size_t i = 0; i < s.size(); ++i) {
        out.mean[i] = s[i] / k;
        out.var[i] = std::max(0.0, (s2[i] - k * out.mean[i] * out.mean[i]) / (k - 1)) / k;
    }
    return out;
}

// Renders `xml` with `runs` seeds (defines applied).
inline std::vector<Cube> render_runs(const std::string& xml, const LoadOptions& options, int runs,
                                     uint64_t first_seed, const std::string& name) {
    std::vector<Cube> out;
    for (int r = 0; r < runs; ++r) {
        auto scene = load_scene_string(xml, options, kScenes);
        out.push_back(test::render_cube(*scene, first_seed + uint64_t(r), name));
    }
    return out;
}

// Two estimators of the same cube agree: the sum over resolved cells of z^2, z = difference of
// the means / sqrt(sum of their variances). Each variance is estimated from `runs` renders, so
// z^2 follows (at worst) a squared t distribution with nu = runs - 1 degrees of freedom, of
// mean nu / (nu - 2) and variance 2 nu^2 (nu - 1) / ((nu - 2)^2 (nu - 4)); the bound is that
// mean plus 3.72 standard deviations of the sum (P ~ 1e-4 one-sided, normal approximation).
// The totals over the cube agree within 4 standard errors.
// A consistent but biased estimator `a` (photon beams) states a bound of its bias as a share of
// the reference's cell, `cell_share`, and of its total, `total_share`: z then counts only what
// exceeds it, z = max(0, |difference| - cell_share x b's cell) / sqrt(sum of variances), which
// leaves a sum no larger than the unbiased one's, and the totals get total_share x b's total on
// top of their 4 standard errors.
inline void expect_agree(const Cells& a, const Cells& b, int runs, const std::string& what,
                         double resolved = 0.3, double min_share = 0.0, double cell_share = 0.0,
                         double total_share = 0.0) {
    const double brightest = *std::max_element(b.mean.begin(), b.mean.end());
    const double nu = runs - 1;
    const double m = nu / (nu - 2), v = 2 * nu * nu * (nu - 1) / ((nu - 2) * (nu - 2) * (nu - 4));
    double chi2 = 0, chi2_plain = 0;
    int n = 0;
    double total_a = 0, total_b = 0, total_var = 0;
    for (size_t i = 0; i < a.mean.size(); ++i) {
        total_a += a.mean[i], total_b += b.mean[i], total_var += a.var[i] + b.var[i];
        const double var = a.var[i] + b.var[i];
        // Resolved: both estimates have a relative error below `resolved`.
        if (!(var > 0) || !(std::sqrt(a.var[i]) < resolved * a.mean[i]) ||
            !(std::sqrt(b.var[i]) < resolved * b.mean[i]) || b.mean[i] < min_share * brightest)
            continue;
        const double d = std::abs(a.mean[i] - b.mean[i]);
        const double z = std::max(0.0, d - cell_share * b.mean[i]) / std::sqrt(var);
        chi2 += z * z;
        chi2_plain += d * d / var;
        ++n;
    }
    ASSERT_GT(n, 20) << what << ": too few resolved cells";
    const double bound = n * m + 3.72 * std::sqrt(n * v);
    const double se_total = std::sqrt(total_var);
    if (cell_share > 0 || total_share > 0)
        std::printf(
            "%s: chi2 %.1f (%.1f without the bias allowance of %.3f) over %d cells, bound %.1f; "
            "totals %.5g vs %.5g (z %.2f, standard error %.3f, allowance %.3f relative)\n",
            what.c_str(), chi2, chi2_plain, cell_share, n, bound, total_a, total_b,
            (total_a - total_b) / se_total, se_total / total_b, total_share);
    EXPECT_LT(chi2, bound) << what << ": chi2 over " << n << " cells (mean " << n * m << ")";
    EXPECT_LT(std::abs(total_a - total_b), 4 * se_total + total_share * total_b)
        << what << ": totals " << total_a << " vs " << total_b << ", standard error " << se_total;
    ::testing::Test::RecordProperty(what + "_total_relative_error",
                                    std::to_string(se_total / total_b));
    ::testing::Test::RecordProperty(what + "_cells", n);
    ::testing::Test::RecordProperty(what + "_chi2",
                                    std::to_string(chi2) + " / bound " + std::to_string(bound));
}

struct AgreementCase {
    std::string scene;
    int max_depth;       // 0: the scene's own
    bool hide_emitters;  // point lights in view: the path tracer never sees them
    std::vector<std::pair<std::string, std::string>> defines;
    int spp_path, spp_light, block, group;
    std::string children = "";       // more XML inside the tested integrator
    std::string path_children = "";  // and inside the reference
    // The reference integrator, rendered with spp_path samples (a light tracer where the path
    // tracer's estimate is dominated by rare events).
    std::string reference = "transient_path";
    // A cell counts when both estimates' relative errors are below this. Cells of rare events
    // (the first light of a dense medium: a few samples per run) have skewed distributions
    // whose spread over 16 runs understates their variance; a lower bound keeps them out.
    double resolved = 0.3;
    // And when the reference holds at least this share of its brightest cell (dim cells at a
    // medium's rim, lit by grazing paths through thin fog, are rare events as well).
    double min_share = 0.0;
};

// `integrator` against transient_path on c.scene; a light tracer is compared only where it can
// see (seen_through_connections()).
inline void check_agreement(const AgreementCase& c,
                            const std::string& integrator = "transient_light") {
    constexpr int kRuns = 16;
    LoadOptions path_options, light_options;
    path_options.defines = light_options.defines = c.defines;
    path_options.defines.push_back({"spp", std::to_string(c.spp_path)});
    light_options.defines.push_back({"spp", std::to_string(c.spp_light)});
    const auto path = render_runs(
        with_integrator(c.scene, c.reference, c.max_depth, c.hide_emitters, c.path_children),
        path_options, kRuns, 100, "agree-path");
    const auto tested =
        render_runs(with_integrator(c.scene, integrator, c.max_depth, c.hide_emitters, c.children),
                    light_options, kRuns, 200, "agree-" + integrator);
    const auto scene =
        load_scene_string(with_integrator(c.scene, "transient_path", c.max_depth, c.hide_emitters),
                          path_options, kScenes);
    const std::vector<bool> mask =
        integrator == "transient_light" || c.reference == "transient_light"
            ? seen_through_connections(*scene)
            : std::vector<bool>();
    ::testing::Test::RecordProperty("tested_integrator", integrator);
    expect_agree(cells_of(tested, c.block, c.group, mask), cells_of(path, c.block, c.group, mask),
                 kRuns, c.scene, c.resolved, c.min_share);
}

// The time-integrated image of `integrator` on `scene` (with `defines`) rendered with seed 3 on
// `threads` threads: equal for 1 and 2 threads when splats merge in a fixed order.
inline std::vector<float> image_with_threads(
    const std::string& scene, const std::string& integrator,
    const std::vector<std::pair<std::string, std::string>>& defines, int threads) {
    LoadOptions options;
    options.defines = defines;
    auto loaded = load_scene_string(with_integrator(scene, integrator, 0, false), options, kScenes);
    RenderOptions opt;
    opt.threads = threads;
    opt.seed = 3;
    render(*loaded, opt);
    return loaded->sensor().film().steady_image();
}

}  // namespace femto::test
