// The integrator conformance matrix, installed with the SDK, run on this folder's mini_path:
// the same analytic checks the built-in integrators pass (tests/unit/test_integrators.cpp).
#include <femto/testing/integrator_conformance.h>

using femto::testing::IntegratorCase;
using femto::testing::IntegratorConformance;

INSTANTIATE_TEST_SUITE_P(Sdk, IntegratorConformance,
                         ::testing::Values(IntegratorCase{
                             "mini_path", "<integer name=\"max_depth\" value=\"$max_depth\"/>", -1,
                             false}),
                         femto::testing::case_name);
