// A thin pane (the thindielectric material) in a transient render: light passes it without
// delay and without being displaced, and with the slab transmittance T' = 1 - 2R / (1 + R).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "femto/host.h"
#include "femto/testing/render.h"

namespace {

using femto::testing::Cube;

/// A camera ray leaves the pane along its own line, so it meets the plane z = 0 at the point
/// straight below its pixel, after exactly the camera's height in optical length.
///
/// An orthographic camera at height 5 looks down on [-1, 1]^2 (8 x 8 pixels of 0.25) at an
/// emitting square [-0.5, 0.5]^2 (radiance 1) through a pane tilted by 45 degrees at z = 2.5.
/// A refracting surface would bend the rays (a single `dielectric` interface turns them by 17
/// degrees, moving the square's image by a pixel and its light to later bins); a thick slab
/// would shift them sideways and delay them by (eta - 1) d / cos. Here the 4 x 4 pixels over
/// the square receive all their light in the bin of time 5 and the others none (up to the ray
/// offset, below). The bin holds
/// T'(45 deg) per pixel: every camera sample passes (weight 1) with probability T', so the mean
/// over those pixels is within 4 binomial standard errors of T'.
TEST(ThinDielectricRender, PaneNeitherDelaysNorDisplaces) {
    const int res = 8, spp = 256, bins = 20;
    const double start = 4.91, width = 0.02;  // time 5 is the middle of bin 4
    const double eta = 1.5;
    const std::string xml =
        "<scene version=\"3.0.0\"><integrator type=\"transient_path\"><integer "
        "name=\"max_depth\" value=\"4\"/></integrator>"
        "<sensor type=\"orthographic\"><transform name=\"to_world\"><lookat origin=\"0,0,5\" "
        "target=\"0,0,0\" up=\"0,1,0\"/></transform><sampler type=\"independent\"><integer "
        "name=\"sample_count\" value=\"" +
        std::to_string(spp) +
        "\"/></sampler><film type=\"transient\"><integer name=\"width\" value=\"8\"/><integer "
        "name=\"height\" value=\"8\"/><float name=\"start\" value=\"4.91\"/><float "
        "name=\"bin_width\" value=\"0.02\"/><integer name=\"bins\" value=\"20\"/><rfilter "
        "type=\"box\"/></film></sensor>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.5\"/>"
        "</transform><bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"0\"/></bsdf>"
        "<emitter type=\"area\"><float name=\"radiance\" value=\"1\"/></emitter></shape>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"1.5\"/><rotate "
        "x=\"1\" angle=\"45\"/><translate z=\"2.5\"/></transform><bsdf "
        "type=\"thindielectric\"><float name=\"int_ior\" value=\"1.5\"/><float name=\"ext_ior\" "
        "value=\"1\"/></bsdf></shape></scene>";
    auto scene = femto::load_scene_string(xml);
    const Cube cube = femto::testing::render_cube(*scene, 7, "thin-pane");
    ASSERT_EQ(cube.T, bins);
    ASSERT_EQ(cube.W, res);
    const int arrival = static_cast<int>(std::floor((5.0 - start) / width));
    ASSERT_EQ(arrival, 4);

    // Every bin but the arrival's is empty everywhere. Pixels off the square may see light
    // only from samples within the ray offset (kRayEpsilon, ~3e-4 here) of its edge, which the
    // pane's tilted normal moves sideways: ~1e-3 of a pixel's samples; at most 2 samples' worth
    // is allowed, where a bent or shifted ray would move a whole row of the square (weight ~1).
    double inside = 0;
    int misplaced = 0;
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) {
            const bool over_square = x >= 2 && x <= 5 && y >= 2 && y <= 5;
            for (int t = 0; t < bins; ++t)
                if (t != arrival && cube.energy(y, x, t) != 0 && ++misplaced <= 5)
                    ADD_FAILURE() << "pixel " << x << "," << y << ": light in bin " << t;
            if (over_square)
                inside += cube.at(y, x, arrival, 0);
            else
                EXPECT_LE(cube.at(y, x, arrival, 0), 2.0 / spp) << "pixel " << x << "," << y;
        }
    EXPECT_EQ(misplaced, 0);

    // T' at 45 degrees from the Fresnel amplitudes of one face (eta = 1.5).
    const double cos_i = std::sqrt(0.5), sin_t = std::sqrt(0.5) / eta;
    const double cos_t = std::sqrt(1 - sin_t * sin_t);
    const double rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    const double rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    const double r = 0.5 * (rs * rs + rp * rp), t_slab = 1 - 2 * r / (1 + r);
    const double n = 16.0 * spp, mean = inside / 16;
    std::printf("[thindielectric] pane at 45 deg: transmitted %.5f, T' = %.5f (R = %.5f)\n", mean,
                t_slab, r);
    EXPECT_NEAR(mean, t_slab, 4 * std::sqrt(t_slab * (1 - t_slab) / n) + 1e-6);
}

}  // namespace
