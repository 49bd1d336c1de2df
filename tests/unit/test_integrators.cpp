// The integrator conformance matrix: every built-in integrator against the analytic checks of
// femto/testing/integrator_conformance.h (the SDK installs the same checks for out-of-tree
// integrators; tests/plugin_sdk runs them on its example). A new integrator joins with one
// line below.
#include "femto/testing/integrator_conformance.h"

using femto::testing::IntegratorCase;
using femto::testing::IntegratorConformance;

namespace {
const std::string kDepth = "<integer name=\"max_depth\" value=\"$max_depth\"/>";
// Photon mapping with kernels small against the checks' scenes (R = 0.02 against a plane of
// 4 x 4 at 1.5 from its light; R = 0.25 in fog whose light is 1 away from the camera ray;
// T = 0.01, two of the tof-plane's bins) and few photons per pass: the checks average over
// passes (their spp) and seeds. Box kernels that keep their size (alpha 1 - 1e-6: they shrink
// by 1e-5 over 20000 passes), which the media check smooths its closed form with.
const std::string kPpm =
    kDepth +
    "<integer name=\"photons_per_pass\" value=\"20000\"/><float name=\"initial_radius\" "
    "value=\"0.02\"/><float name=\"volume_initial_radius\" value=\"0.25\"/><float "
    "name=\"initial_bandwidth\" value=\"0.01\"/><string name=\"spatial_kernel\" "
    "value=\"box\"/><string name=\"temporal_kernel\" value=\"box\"/><float name=\"alpha\" "
    "value=\"0.999999\"/><float name=\"volume_alpha\" value=\"0.999999\"/>";
// Photon beams: the same fixed box kernels in fog (a blur of 0.25 across each beam, T = 0.01);
// surfaces are path traced, so only the media check has a kernel.
const std::string kBeams =
    kDepth +
    "<integer name=\"photons_per_pass\" value=\"2000\"/><float name=\"initial_radius\" "
    "value=\"0.25\"/><float name=\"initial_bandwidth\" value=\"0.01\"/><string "
    "name=\"spatial_kernel\" value=\"box\"/><string name=\"temporal_kernel\" "
    "value=\"box\"/><float name=\"alpha\" value=\"0.999999\"/>";
}  // namespace

INSTANTIATE_TEST_SUITE_P(
    Builtin, IntegratorConformance,
    ::testing::Values(IntegratorCase{"path", kDepth, -1, true},
                      IntegratorCase{"transient_path", kDepth, -1, true},
                      IntegratorCase{"direct", "", 2, false},
                      IntegratorCase{"transient_light", kDepth, -1, true, true},
                      IntegratorCase{"transient_bdpt", kDepth, -1, true},
                      IntegratorCase{"bdpt", kDepth, -1, true},
                      IntegratorCase{"volpath", kDepth, -1, true},
                      IntegratorCase{"transient_ppm", kPpm, -1, true, false, 0.02, 0.01, 0.25},
                      IntegratorCase{.type = "transient_beams",
                                     .parameters = kBeams,
                                     .media = true,
                                     .volume_radius = 0.25,
                                     .volume_dims = 1,
                                     .volume_time = 0.01,
                                     .media_only = true}),
    femto::testing::case_name);
