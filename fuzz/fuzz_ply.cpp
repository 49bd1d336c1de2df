// libFuzzer harness: the bytes of a .ply file, read by the `ply` shape plugin (created as the
// loader creates it, with its schema checked). The file name's location makes errors located.
#include <cstddef>
#include <cstdint>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    femto::fuzz::read_plugin_file(femto::PluginKind::Shape, "ply", "filename", "input.ply", data,
                                  size);
    return 0;
}
