// libFuzzer harness: the bytes of a .serialized file, read by the `serialized` shape plugin
// (created as the loader creates it, with its schema checked). The file name's location makes
// errors located.
#include <cstddef>
#include <cstdint>
#include <string>

#include "femto/host.h"
#include "femto/properties.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = femto::fuzz::write_scratch("input.serialized", data, size);
    femto::fuzz::run([&] {
        femto::Properties props("serialized", {"fuzz.xml", 1, 1});
        props.set("filename", femto::Properties::Type::String, path, {"fuzz.xml", 2, 5});
        femto::create_object(femto::PluginKind::Shape, "serialized", props);
    });
    return 0;
}
