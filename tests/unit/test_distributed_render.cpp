// A distributed render without MPI: the processes of a job are played one after the other in
// this process (each a PassGroup of its own rank), and their films are combined as rank 0
// combines them (render/combine.h). Together they must give the single-process image.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <deque>
#include <string>
#include <vector>

#include "femto/film.h"
#include "femto/host.h"
#include "femto/integrator.h"
#include "femto/scene.h"
#include "femto/sensor.h"
#include "render/combine.h"

namespace femto {
namespace {

// Process `rank` of `size`; the processes never run at once here, so a stop vote is local.
class PlayedProcess final : public PassGroup {
public:
    PlayedProcess(int rank, int size) : rank_(rank), size_(size) {}
    int rank() const override { return rank_; }
    int size() const override { return size_; }
    bool any(bool stop) override { return stop; }

private:
    int rank_, size_;
};

std::unique_ptr<Scene> render_scene(const std::string& file, const LoadOptions& lo,
                                    PassGroup* group) {
    auto scene = load_scene(std::string(FEMTO_SOURCE_DIR) + "/" + file, lo);
    RenderOptions ro;
    ro.seed = 11;
    ro.threads = 2;
    ro.group = group;
    render(*scene, ro);
    return scene;
}

std::vector<Accumulator> totals(Scene& scene) {
    std::vector<Accumulator> all = scene.sensor().film().accumulators();
    for (const Accumulator& a : scene.integrator().accumulators()) all.push_back(a);
    return all;
}

// Renders `file` in one process and as `processes` processes, combines the latter into rank
// 0's film, and compares the steady images to relative `tolerance` (float rounding).
void expect_same_image(const std::string& file, const LoadOptions& lo, int processes) {
    const auto single = render_scene(file, lo, nullptr);
    std::vector<std::unique_ptr<Scene>> parts;
    for (int r = 0; r < processes; ++r) {
        PlayedProcess group(r, processes);
        parts.push_back(render_scene(file, lo, &group));
    }
    const std::vector<float> rank0_alone = parts[0]->sensor().film().steady_image();
    std::vector<std::deque<std::vector<char>>> sent(static_cast<size_t>(processes));
    for (int r = 1; r < processes; ++r)
        send_accumulators(totals(*parts[size_t(r)]), 4096, [&](const void* data, size_t bytes) {
            const char* p = static_cast<const char*>(data);
            sent[size_t(r)].emplace_back(p, p + bytes);
        });
    combine_accumulators(totals(*parts[0]), processes, 4096,
                         [&](int r, void* buffer, size_t bytes) {
                             ASSERT_EQ(sent[size_t(r)].front().size(), bytes);
                             std::memcpy(buffer, sent[size_t(r)].front().data(), bytes);
                             sent[size_t(r)].pop_front();
                         });
    const std::vector<float> a = single->sensor().film().steady_image();
    const std::vector<float> b = parts[0]->sensor().film().steady_image();
    ASSERT_EQ(a.size(), b.size());
    size_t differing_alone = 0, nonzero = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        nonzero += a[i] != 0;
        differing_alone += std::abs(rank0_alone[i] - a[i]) > 1e-3f * std::abs(a[i]);
        ASSERT_NEAR(b[i], a[i], 1e-6 * std::max(std::abs(a[i]), std::abs(b[i])))
            << file << " value " << i;
    }
    ASSERT_GT(nonzero, 0u) << "no light reached the film";
    // Rank 0's own passes alone are another (noisier) estimate: the combination mattered.
    EXPECT_GT(differing_alone, nonzero / 2);
}

TEST(DistributedRender, PathIntoHdrfilm) {
    LoadOptions lo;
    lo.defines = {{"integrator", "path"}, {"film", "hdrfilm"}, {"res", "24"}, {"spp", "16"}};
    expect_same_image("bench/experiments/scenes/cornell-films.xml", lo, 3);
}

TEST(DistributedRender, TransientPathWithTheKernelFilter) {
    // The kernel's 64-sample pilot is the image's first samples: every process traces it (for
    // the bandwidths), rank 0 keeps it, and the 64 samples after it are shared out by passes.
    LoadOptions lo;
    lo.defines = {{"tfilter", "kernel"}, {"res", "24"}, {"spp", "128"}, {"bins", "32"}};
    expect_same_image("scenes/cornell-box/scene.xml", lo, 2);
}

TEST(DistributedRender, LightTracer) {
    LoadOptions lo;
    lo.defines = {{"integrator", "transient_light"}, {"res", "24"}, {"spp", "8"}, {"bins", "32"}};
    expect_same_image("scenes/cornell-box/scene.xml", lo, 3);
}

}  // namespace
}  // namespace femto
