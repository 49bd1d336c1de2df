// libFuzzer harness: the bytes of an EXR image, read as the `bitmap` texture's file (created as
// the loader creates it, with its schema checked). A file with EXR's magic number goes through
// femto's OpenEXR reader, which reads half or float R, G and B and passes other channels, like
// a file without the magic number, to the OpenImageIO module: both readers see mutated files.
#include <cstddef>
#include <cstdint>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    femto::fuzz::read_plugin_file(femto::PluginKind::Texture, "bitmap", "filename", "input.exr",
                                  data, size);
    return 0;
}
