// libFuzzer harness: the bytes of a Mitsuba .vol density grid, read by the `heterogeneous`
// medium plugin (created as the loader creates it, with its schema checked).
#include <cstddef>
#include <cstdint>
#include <string>

#include "femto/host.h"
#include "femto/properties.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = femto::fuzz::write_scratch("input.vol", data, size);
    femto::fuzz::run([&] {
        femto::Properties props("heterogeneous", {"fuzz.xml", 1, 1});
        props.set("density", femto::Properties::Type::String, path, {"fuzz.xml", 2, 5});
        femto::create_object(femto::PluginKind::Medium, "heterogeneous", props);
    });
    return 0;
}
