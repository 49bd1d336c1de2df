// Mutation test: thousands of randomly corrupted versions of the demo scene are loaded (run
// under AddressSanitizer + UBSan in the FEMTO_SANITIZE build). Each must load or fail with a
// SceneError; anything else (another exception, a crash, a sanitizer report) fails the test.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <sstream>

#include "femto/host.h"
#include "femto/random.h"

namespace {

std::string read(const std::string& path) {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

const char* const kSnippets[] = {"<",
                                 ">",
                                 "\"",
                                 "/>",
                                 "$",
                                 "$res",
                                 "0",
                                 "-1",
                                 "1e40",
                                 "nan",
                                 "inf",
                                 "-0",
                                 "99999999",
                                 "4294967297",
                                 "&amp;",
                                 "<shape",
                                 "</",
                                 "id=\"white\"",
                                 "<ref id=\"x\"/>",
                                 "<include filename=\"scene.xml\"/>",
                                 "type=\"sphere\"",
                                 "name=\"\"",
                                 "<float name=\"radius\" value=\"-2\"/>",
                                 "\x01",
                                 "\xff\xfe",
                                 "]]>"};

std::string mutate(const std::string& base, femto::Pcg32& rng) {
    std::string s = base;
    const int edits = 1 + int(rng.next_u32() % 4);
    for (int e = 0; e < edits && !s.empty(); ++e) {
        const size_t pos = rng.next_u32() % s.size();
        const size_t len = 1 + rng.next_u32() % 24;
        switch (rng.next_u32() % 6) {
            case 0:
                s.erase(pos, len);
                break;  // delete
            case 1:
                s.insert(pos, kSnippets[rng.next_u32() % std::size(kSnippets)]);
                break;
            case 2:
                s.insert(pos, s.substr(rng.next_u32() % s.size(), len));
                break;  // duplicate
            case 3:
                s[pos] = char(rng.next_u32() & 0xff);
                break;  // flip a byte
            case 4:
                s.resize(pos);
                break;  // truncate
            case 5: {   // replace a number
                const size_t d = s.find_first_of("0123456789", pos);
                if (d == std::string::npos) break;
                size_t end = s.find_first_not_of("0123456789.", d);
                if (end == std::string::npos) end = s.size();
                const char* values[] = {"0", "-1", "1e38", "nan", "1e-40", "65537", "8193", "-90"};
                s.replace(d, end - d, values[rng.next_u32() % std::size(values)]);
                break;
            }
        }
    }
    return s;
}

}  // namespace

TEST(Mutation, CorruptedDemoScenesGiveCleanErrors) {
    const std::string dir = std::string(FEMTO_SOURCE_DIR) + "/scenes/cornell-box";
    const std::string base = read(dir + "/scene.xml");
    ASSERT_FALSE(base.empty());
    femto::Pcg32 rng(2026, 11);
    femto::LoadOptions options;
    options.defines = {{"res", "16"}};  // keep accepted films small; mutations may still change it
    int loaded = 0, rejected = 0;
    const auto start = std::chrono::steady_clock::now();
    constexpr int kMutations = 3000;
    for (int i = 0; i < kMutations; ++i) {
        const std::string xml = mutate(base, rng);
        const auto t0 = std::chrono::steady_clock::now();
        try {
            femto::load_scene_string(xml, options, dir);
            ++loaded;
        } catch (const femto::SceneError&) {
            ++rejected;
        } catch (const std::exception& e) {
            FAIL() << "mutation " << i << " threw a non-SceneError: " << e.what() << "\n" << xml;
        }
        const double secs =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        ASSERT_LT(secs, 20.0) << "mutation " << i << " took " << secs << " s to load:\n" << xml;
    }
    const double total =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("%d mutations: %d loaded, %d rejected with a SceneError, %.1f s\n", kMutations,
                loaded, rejected, total);
    EXPECT_GT(rejected, kMutations / 2);  // the mutations do break the scene
    EXPECT_GT(loaded, 0);                 // and some are harmless
}
