// libFuzzer harness: the bytes of a Mitsuba .vol density grid, read by the `heterogeneous`
// medium plugin (created as the loader creates it, with its schema checked).
#include <cstddef>
#include <cstdint>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    femto::fuzz::read_plugin_file(femto::PluginKind::Medium, "heterogeneous", "density",
                                  "input.vol", data, size);
    return 0;
}
