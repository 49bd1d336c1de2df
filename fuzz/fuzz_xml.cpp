// libFuzzer harness: a scene file, loaded as the CLI loads it (femto::load_scene with the built
// plugins: parse, passes, instantiation, the Embree scene). Never renders.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "femto/host.h"
#include "fuzz_common.h"

namespace {

// The scene goes to a file next to copies of the seed meshes and grids (ply/, obj/,
// serialized/, vol/; see make_seeds.py), so that mutated scenes naming them reach the mesh and
// .vol readers by relative names, as real scenes do.
std::string prepare_scene_dir() {
    namespace fs = std::filesystem;
    const fs::path dir = femto::fuzz::scratch_dir();
    for (const char* kind : {"ply", "obj", "serialized", "vol"})
        fs::copy(fs::path(FEMTO_FUZZ_SEED_DIR) / kind, dir / kind,
                 fs::copy_options::recursive | fs::copy_options::overwrite_existing);
    return dir.string();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const std::string dir = prepare_scene_dir();
    (void)dir;
    const std::string path = femto::fuzz::write_scratch("scene.xml", data, size);
    femto::fuzz::run([&] { femto::load_scene(path); });
    return 0;
}
