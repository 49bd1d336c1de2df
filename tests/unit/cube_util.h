// Helpers for tests of transient renders: the SDK's testing kit (femto/testing/render.h)
// under the names the unit tests use.
#pragma once

#include "femto/testing/render.h"
#include "scene_util.h"

namespace femto::test {

using femto::testing::Cube;
using femto::testing::read_npy;
using femto::testing::render_cube;
using femto::testing::render_cube_and_variance;
using femto::testing::render_cubes;

}  // namespace femto::test
