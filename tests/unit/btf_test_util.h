// The small synthetic BTF the BTF tests share (btf/synth.h, docs/btf.md): BTF A on a
// non-square texture (which catches x/y mix-ups) with UBO2003's 81 directions (small files).
#pragma once

#include <string>

#include "btf/synth.h"
#include "femto/testing/render.h"

namespace femto::test {

inline btf::synth::Options small_btf_a(btf::Format format = btf::Format::Dfmf) {
    btf::synth::Options o;
    o.format = format;
    o.width = 8;
    o.height = 4;
    o.directions = btf::ubo2003_directions();
    return o;
}

/// Writes the synthetic BTF `o` as `name` in the temporary folder `folder`; returns its path.
inline std::string write_btf(const btf::synth::Options& o, const std::string& folder,
                             const std::string& name) {
    const std::string path = (femto::testing::temp_dir(folder) / name).string();
    btf::synth::write(path, o);
    return path;
}

}  // namespace femto::test
