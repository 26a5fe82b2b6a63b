// Whole-renderer tests: the white furnace (an analytic answer), thread-count determinism and cancellation.
#include <gtest/gtest.h>

#include <atomic>
#include <cstring>

#include "integrators/integrator.h"
#include "render/renderer.h"
#include "scene/gltf_loader.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

void expectFurnace(const Scene& scene, Rgb albedo, Rgb Le, int spp) {
    test::TestRender r = test::renderScene(scene, "ptnee", 48, 48, RenderOptions{.spp = spp, .seed = 1234});
    const Film& film = r.film;
    RenderStats stats = r.stats;
    EXPECT_EQ(stats.nonFiniteDropped, 0u);
    double mean[3], se[3];
    test::pixelMean(film, mean, se);
    for (int c = 0; c < 3; ++c) {
        double expected = Le[c] / (1.0 - albedo[c]);
        double err = std::abs(mean[c] - expected);
        EXPECT_LT(err, 3.0 * se[c]) << "channel " << c << " mean " << mean[c] << " expected " << expected << " se " << se[c];
        EXPECT_LT(err, 0.005 * expected) << "channel " << c << " mean " << mean[c] << " expected " << expected;
    }
}

}  // namespace

TEST(Furnace, AnalyticSphereGivesLeOverOneMinusAlbedo) {
    Rgb albedo(0.5f, 0.3f, 0.8f), Le(1.f, 2.f, 0.5f);
    expectFurnace(test::closedSphere(albedo, Le, false), albedo, Le, 96);
}

TEST(Furnace, TriangleMeshSphereGivesLeOverOneMinusAlbedo) {
    Rgb albedo(0.6f), Le(1.f);
    expectFurnace(test::closedSphere(albedo, Le, true), albedo, Le, 96);
}

TEST(Determinism, OneAndTwoThreadsGiveTheSameBits) {
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(test::sourcePath("scenes/cornell-box/cornell-box.gltf"), warnings);
    std::vector<float> images[2];
    for (int threads : {1, 2})
        images[threads - 1] =
            test::renderScene(scene, "ptnee", 80, 60, RenderOptions{.spp = 8, .threads = threads, .seed = 7, .tileSize = 16})
                .film.rgba();
    ASSERT_EQ(images[0].size(), images[1].size());
    EXPECT_EQ(std::memcmp(images[0].data(), images[1].data(), images[0].size() * sizeof(float)), 0);
    double sum = 0;
    for (float v : images[0]) sum += v;
    EXPECT_GT(sum, 0.0);
}

namespace {
/// ptnee that raises `cancel` once it has taken `cancelAfter` samples, as Ctrl-C would mid-render.
class CancellingIntegrator final : public Integrator {
public:
    CancellingIntegrator(std::atomic<bool>& cancel, uint64_t cancelAfter) : cancel_(cancel), cancelAfter_(cancelAfter) {}
    std::string_view name() const override { return "ptnee"; }
    Rgb sample(const RenderContext& ctx, Vec2i pixel, Vec2f raster, Sampler& sampler, SplatSink& splats) const override {
        if (taken_.fetch_add(1) + 1 == cancelAfter_) cancel_.store(true);
        return ptnee_->sample(ctx, pixel, raster, sampler, splats);
    }

private:
    std::unique_ptr<Integrator> ptnee_ = createIntegrator("ptnee");
    std::atomic<bool>& cancel_;
    uint64_t cancelAfter_;
    mutable std::atomic<uint64_t> taken_{0};
};
}  // namespace

// Cancelled inside the second pass (passes take 1, 1, 2 spp): the scheduler finishes the tiles it
// has started, skips the rest, and the film keeps the complete first pass plus those tiles, each
// pixel bit-identical to an uninterrupted render with the same number of samples.
TEST(Render, CancelledRenderStopsAndKeepsWhatItHas) {
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(test::sourcePath("scenes/cornell-box/cornell-box.gltf"), warnings);
    auto accel = createAccel("embree", scene.geometry);
    const int size = 64, tileSize = 16;
    const uint64_t pixels = uint64_t(size) * size;
    std::atomic<bool> cancel{false};
    CancellingIntegrator cancelling(cancel, /* cancelAfter = */ pixels + 1);  // the second pass's first sample
    RenderOptions opt{.spp = 4, .threads = 2, .seed = 5, .tileSize = tileSize, .cancel = &cancel};
    test::TestRender cut = test::renderScene(scene, *accel, cancelling, size, size, opt);
    EXPECT_TRUE(cut.stats.interrupted);
    EXPECT_EQ(cut.stats.sppCompleted, 1u);

    auto ptnee = createIntegrator("ptnee");
    auto uninterrupted = [&](int spp) {
        return test::renderScene(scene, *accel, *ptnee, size, size, RenderOptions{.spp = spp, .threads = 2, .seed = 5, .tileSize = tileSize})
            .film;
    };
    Film oneSpp = uninterrupted(1), twoSpp = uninterrupted(2);
    uint64_t secondPassPixels = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            uint32_t n = cut.film.sampleCount(x, y);
            ASSERT_TRUE(n == 1 || n == 2) << x << "," << y << ": " << n << " samples";
            secondPassPixels += n - 1;
            const Film& same = n == 1 ? oneSpp : twoSpp;
            for (int c = 0; c < 3; ++c) ASSERT_EQ(cut.film.pixel(x, y)[c], same.pixel(x, y)[c]) << x << "," << y;
        }
    // Whole tiles of the second pass, at least the one that raised the flag, and not all of them.
    EXPECT_EQ(secondPassPixels % uint64_t(tileSize * tileSize), 0u);
    EXPECT_GE(secondPassPixels, uint64_t(tileSize * tileSize));
    EXPECT_LT(secondPassPixels, pixels);
    EXPECT_EQ(cut.stats.samples, pixels + secondPassPixels);
}
