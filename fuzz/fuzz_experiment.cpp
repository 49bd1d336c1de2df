// libFuzzer harness: the bytes of a `femto bench` experiment file, read by
// femto::bench::load_experiment (the XML, its elements and attributes, numbers, names, the
// budgets and seeds). The files it names must exist: the harness writes the input next to an
// empty `scene.xml` and a folder `plugins`, which the seeds (make_seeds.py: the experiments of
// bench/experiments with every file named scene.xml) refer to. Loading never renders.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>

#include "bench/experiment.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const bool files_made = [] {
        const std::filesystem::path dir(femto::fuzz::scratch_dir());
        std::ofstream(dir / "scene.xml") << "<scene version=\"3.0.0\"/>\n";
        std::filesystem::create_directories(dir / "plugins");
        return true;
    }();
    (void)files_made;
    const std::string path = femto::fuzz::write_scratch("experiment.xml", data, size);
    femto::fuzz::run([&] { femto::bench::load_experiment(path); });
    return 0;
}
