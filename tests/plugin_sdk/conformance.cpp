// The integrator conformance matrix, installed with the SDK, run on this folder's mini_path
// and mini_light: the same analytic checks the built-in integrators pass
// (tests/unit/test_integrators.cpp).
#include <femto/testing/integrator_conformance.h>

using femto::testing::IntegratorCase;
using femto::testing::IntegratorConformance;

namespace {
const std::string kDepth = "<integer name=\"max_depth\" value=\"$max_depth\"/>";
}  // namespace

INSTANTIATE_TEST_SUITE_P(Sdk, IntegratorConformance,
                         ::testing::Values(IntegratorCase{"mini_path", kDepth, -1, false},
                                           IntegratorCase{"mini_light", kDepth, -1, false, true}),
                         femto::testing::case_name);
