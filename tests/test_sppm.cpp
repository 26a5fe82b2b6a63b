// `sppm` (integrators/sppm.h): consistent, not unbiased, so it is judged by what consistency
// promises: the analytic furnaces within 1% after some iterations, the error against an
// independent reference falling with iterations, the image mean agreeing with the reference;
// and, like every integrator, the same bits for any thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "integrators/sppm.h"
#include "render/renderer.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

Film renderSppm(const Scene& scene, int w, int h, int spp, uint64_t seed, int threads, PhotonSettings settings = {}) {
    auto accel = createAccel("embree", scene.geometry);
    SppmIntegrator sppm(settings);
    RenderOptions opt{.spp = spp, .threads = threads, .seed = seed, .tileSize = 16};
    test::TestRender r = test::renderScene(scene, *accel, sppm, w, h, opt, -1);
    EXPECT_EQ(r.stats.nonFiniteDropped, 0u);
    return std::move(r.film);
}

void expectMeanWithin(const Film& film, Rgb expected, double relTol, const std::string& what) {
    double mean[3], se[3];
    test::pixelMean(film, mean, se);
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(mean[c], expected[c], relTol * expected[c]) << what << " channel " << c;
}

/// relMSE (as `tessera compare`: mean of (x − r)² / (r² + 0.01)) of a film against an image.
double relMseAgainst(const Film& film, const io::Image& ref) {
    std::vector<float> rgba = film.rgba();
    double sum = 0;
    size_t n = 0;
    for (size_t i = 0; i < rgba.size(); ++i) {
        if (i % 4 == 3) continue;
        double d = double(rgba[i]) - ref.rgba[i], r = ref.rgba[i];
        sum += d * d / (r * r + 0.01);
        ++n;
    }
    return sum / double(n);
}

}  // namespace

TEST(Sppm, RadiusFollowsKnausZwickerSequence) {
    // r_(i+1)² = r_i² (i + α)/(i + 1) from r_1 at sample index 0; shrinking, never to zero in finite i.
    EXPECT_EQ(photonIterationRadius(2.f, 0.75f, 0), 2.f);
    EXPECT_FLOAT_EQ(photonIterationRadius(2.f, 0.75f, 1), 2.f * std::sqrt(1.75f / 2.f));
    EXPECT_FLOAT_EQ(photonIterationRadius(2.f, 0.75f, 2), 2.f * std::sqrt(1.75f / 2.f * 2.75f / 3.f));
    float r100 = photonIterationRadius(1.f, 0.75f, 100), r1000 = photonIterationRadius(1.f, 0.75f, 1000);
    EXPECT_LT(r1000, r100);
    // r_i² ∝ i^(α−1) for large i: ten times the iterations, 10^(−0.125) times the radius.
    EXPECT_NEAR(r1000 / r100, std::pow(10.0, -0.125), 0.01);
}

// Closed sphere, uniform emission Le and albedo a: L = Le / (1 − a) everywhere (the furnace every
// integrator passes); and a point light at the centre of a closed sphere, L = a I / (π R² (1 − a)).
TEST(Sppm, FurnacesWithinOnePercent) {
    Rgb albedo(0.5f, 0.3f, 0.7f), Le(1.f, 2.f, 0.5f);
    for (bool asMesh : {false, true}) {
        Scene scene = test::closedSphere(albedo, Le, asMesh);
        expectMeanWithin(renderSppm(scene, 32, 32, 256, 99, 2), Le / (Rgb(1.f) - albedo), 0.01, asMesh ? "mesh sphere" : "sphere");
    }
    Rgb I(2.f, 1.f, 3.f);
    Scene scene = test::closedSphere(albedo, Rgb(0.f), false, {PointLightDesc{Vec3f(0.1f, -0.2f, 0.05f), I}});
    expectMeanWithin(renderSppm(scene, 32, 32, 128, 5, 2), albedo * I / (kPi * (Rgb(1.f) - albedo)), 0.015, "point light");
}

// Against the Cornell box's reference (bdpt, ptnee and Cycles agreeing: refs/README.md): the error
// at 64 iterations is well below that at 4 (variance falls as i^−α, squared bias as i^−2(1−α):
// 16 times the iterations divide the MSE by 4 to 8), and the mean agrees within 1%.
TEST(Sppm, ErrorFallsWithIterationsAgainstAnIndependentReference) {
    Scene scene = test::loadSourceScene("scenes/cornell-box/cornell-box.gltf");
    io::Image ref = test::boxDownsample(io::readImage(test::sourcePath("refs/cornell-box.exr")), 4, false);
    ASSERT_EQ(ref.width, 64);
    Film few = renderSppm(scene, 64, 64, 4, 21, 2), many = renderSppm(scene, 64, 64, 64, 21, 2);
    double e4 = relMseAgainst(few, ref), e64 = relMseAgainst(many, ref);
    EXPECT_LT(e64, 0.35 * e4) << "relMSE " << e4 << " at 4 iterations, " << e64 << " at 64";
    double mean[3], se[3], refMean[3] = {0, 0, 0};
    test::pixelMean(many, mean, se);
    for (size_t i = 0; i < ref.rgba.size(); ++i)
        if (i % 4 != 3) refMean[i % 4] += ref.rgba[i] / double(ref.width * ref.height);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], refMean[c], 0.01 * refMean[c]) << "channel " << c;
}

TEST(Sppm, BitIdenticalForOneAndTwoThreads) {
    Scene scene = test::loadSourceScene("scenes/cornell-box/cornell-box.gltf");
    std::vector<float> images[2];
    for (int threads : {1, 2}) images[threads - 1] = renderSppm(scene, 48, 40, 3, 7, threads).rgba();
    ASSERT_EQ(images[0].size(), images[1].size());
    EXPECT_EQ(std::memcmp(images[0].data(), images[1].data(), images[0].size() * sizeof(float)), 0);
}

// Kernel bias, and its shrinking: a point light 0.4 from the wall of the closed sphere (R = 1,
// albedo a) makes the direct irradiance peak where the camera looks. The radiance is analytic,
// L(x) = a/π (I cos θ / d² + a I / ((1 − a) R²)) (indirect light in a sphere is uniform: every form
// factor is dA/(4π R²)), and a merge blurs the peak over r (the cap within r of x has area exactly
// π r² on a sphere, so the blur is the only bias). With r_1 = 0.3 and α = 0.5 the peak region's
// mean is clearly low after 4 iterations and at most half as low after 64: the average of r_i²
// over the iterations falls as i^(α−1), a factor 0.34 from 4 to 64 (measured: −6.5% and −2.4%).
TEST(Sppm, KernelBiasAtAnIrradiancePeakShrinksWithIterations) {
    const Rgb albedo(0.5f);
    const float I = 1.f, a = 0.5f;
    const Vec3f centre(0.1f, -0.2f, 0.05f), light = centre + Vec3f(0.f, 0.f, -0.6f);
    Scene scene = test::closedSphere(albedo, Rgb(0.f), false, {PointLightDesc{light, Rgb(I)}});
    const int w = 48, h = 48;
    Camera camera(*scene.camera, w, h);
    // Analytic radiance at each pixel centre's hit, and the peak region (within 0.35 of the point
    // nearest the light).
    const Vec3f peak = centre + Vec3f(0.f, 0.f, -1.f);
    std::vector<double> expected(size_t(w * h), 0.0);
    std::vector<bool> region(size_t(w * h), false);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            Ray ray = camera.generateRay(Vec2f(float(x) + 0.5f, float(y) + 0.5f), Vec2f(0.5f));
            Vec3f d = glm::normalize(ray.d), oc = ray.o - centre;
            float b = glm::dot(oc, d), t = -b + std::sqrt(b * b - (glm::dot(oc, oc) - 1.f));
            Vec3f p = ray.o + t * d, toLight = light - p;
            float dist2 = glm::dot(toLight, toLight);
            float cosTheta = glm::dot(glm::normalize(centre - p), toLight / std::sqrt(dist2));
            expected[size_t(y * w + x)] = a / kPi * (I * cosTheta / dist2 + a * I / (1.f - a));
            region[size_t(y * w + x)] = glm::length(p - peak) < 0.35f;
        }
    ASSERT_GT(std::count(region.begin(), region.end(), true), 50);
    auto regionBias = [&](int iterations) {
        Film film = renderSppm(scene, w, h, iterations, 17, 2, PhotonSettings{.radius = 0.3f, .alpha = 0.5f, .photons = 40000});
        double got = 0.0, want = 0.0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                if (region[size_t(y * w + x)]) got += film.pixel(x, y).g, want += expected[size_t(y * w + x)];
        return got / want - 1.0;
    };
    const double few = regionBias(4), many = regionBias(64);
    std::cout << "peak region bias: " << few * 100.0 << "% after 4 iterations, " << many * 100.0 << "% after 64\n";
    EXPECT_LT(few, -0.02) << "the blur must show at r = 0.3";
    EXPECT_LT(std::abs(many), 0.5 * std::abs(few));
}
