// Whole-renderer tests: the white furnace (an analytic answer) and thread-count determinism.
#include <gtest/gtest.h>

#include <cstring>

#include "integrators/integrator.h"
#include "render/renderer.h"
#include "scene/gltf_loader.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

void expectFurnace(const Scene& scene, Rgb albedo, Rgb Le, int spp) {
    auto accel = createAccel("embree", scene.geometry);
    auto integrator = createIntegrator("ptnee");
    Camera camera(*scene.camera, 48, 48);
    RenderContext ctx{scene, *accel, camera, -1};
    Film film(48, 48);
    RenderOptions opt{.spp = spp, .seed = 1234};
    RenderStats stats = renderImage(ctx, *integrator, film, opt);
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
    auto accel = createAccel("embree", scene.geometry);
    auto integrator = createIntegrator("ptnee");
    Camera camera(*scene.camera, 80, 60);
    RenderContext ctx{scene, *accel, camera, -1};
    std::vector<float> images[2];
    for (int threads : {1, 2}) {
        Film film(80, 60);
        RenderOptions opt{.spp = 8, .threads = threads, .seed = 7, .tileSize = 16};
        renderImage(ctx, *integrator, film, opt);
        images[threads - 1] = film.rgba();
    }
    ASSERT_EQ(images[0].size(), images[1].size());
    EXPECT_EQ(std::memcmp(images[0].data(), images[1].data(), images[0].size() * sizeof(float)), 0);
    double sum = 0;
    for (float v : images[0]) sum += v;
    EXPECT_GT(sum, 0.0);
}

TEST(Render, CancelledRenderStopsAndKeepsWhatItHas) {
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(test::sourcePath("scenes/cornell-box/cornell-box.gltf"), warnings);
    auto accel = createAccel("embree", scene.geometry);
    auto integrator = createIntegrator("ptnee");
    Camera camera(*scene.camera, 64, 64);
    RenderContext ctx{scene, *accel, camera, -1};
    Film film(64, 64);
    std::atomic<bool> cancel{true};
    RenderOptions opt{.spp = 4, .cancel = &cancel};
    RenderStats stats = renderImage(ctx, *integrator, film, opt);
    EXPECT_TRUE(stats.interrupted);
    EXPECT_EQ(stats.sppCompleted, 0u);
}
