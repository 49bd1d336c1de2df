// The integrator conformance matrix: every built-in integrator against the analytic checks of
// femto/testing/integrator_conformance.h (the SDK installs the same checks for out-of-tree
// integrators; tests/plugin_sdk runs them on its example). A new integrator joins with one
// line below.
#include "femto/testing/integrator_conformance.h"

using femto::testing::IntegratorCase;
using femto::testing::IntegratorConformance;

namespace {
const std::string kDepth = "<integer name=\"max_depth\" value=\"$max_depth\"/>";
}  // namespace

INSTANTIATE_TEST_SUITE_P(Builtin, IntegratorConformance,
                         ::testing::Values(IntegratorCase{"path", kDepth, -1, true},
                                           IntegratorCase{"transient_path", kDepth, -1, true},
                                           IntegratorCase{"direct", "", 2, false},
                                           IntegratorCase{"transient_light", kDepth, -1, true,
                                                          true},
                                           IntegratorCase{"transient_bdpt", kDepth, -1, true},
                                           IntegratorCase{"bdpt", kDepth, -1, true},
                                           IntegratorCase{"volpath", kDepth, -1, true}),
                         femto::testing::case_name);
