// libFuzzer harness: the bytes of a Bonn BTF file (BDI, DFMF or FMF), read by the `btf`
// material plugin (created as the loader creates it, with its schema checked).
#include <cstddef>
#include <cstdint>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    femto::fuzz::read_plugin_file(femto::PluginKind::Bsdf, "btf", "filename", "input.btf", data,
                                  size);
    return 0;
}
