// `vcm` (integrators/vcm.h): bdpt's connections and sppm's merges under one MIS weight. Judged as
// its parts are: without merging it must be bdpt bit for bit; with merging it is consistent, so
// the analytic furnaces within 1%, the Cornell box's mean against its independent reference, the
// SDS caustic (which only merging samples well) far below bdpt's error at equal samples; and the
// same bits for any thread count. The weights themselves are checked against brute force in
// test_bdpt_mis.cpp (VcmMis).
#include <gtest/gtest.h>

#include <cstring>

#include "integrators/bdpt.h"
#include "integrators/vcm.h"
#include "render/renderer.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

Film renderVcmTest(const Scene& scene, const Integrator& integrator, int w, int h, int spp, uint64_t seed, int threads) {
    auto accel = createAccel("embree", scene.geometry);
    RenderOptions opt{.spp = spp, .threads = threads, .seed = seed, .tileSize = 16};
    test::TestRender r = test::renderScene(scene, *accel, integrator, w, h, opt, -1);
    EXPECT_EQ(r.stats.nonFiniteDropped, 0u);
    return std::move(r.film);
}

bool sameBits(const Film& a, const Film& b) {
    std::vector<float> x = a.rgba(), y = b.rgba();
    return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(float)) == 0;
}

/// Luminance relMSE (tools/study_metrics.py's (x − r)² / (r² + 0.01)) of a film against an image.
double lumaRelMseAgainst(const Film& film, const io::Image& ref) {
    double sum = 0;
    for (int j = 0; j < ref.height; ++j)
        for (int i = 0; i < ref.width; ++i) {
            Rgb p = film.pixel(i, j);
            const float* r = &ref.rgba[(size_t(j) * size_t(ref.width) + size_t(i)) * 4];
            double x = luminance(p), y = luminance(Rgb(r[0], r[1], r[2]));
            sum += (x - y) * (x - y) / (y * y + 0.01);
        }
    return sum / double(ref.width * ref.height);
}

double imageMeanLuminance(const io::Image& img) {
    double sum = 0;
    for (size_t i = 0; i < img.rgba.size(); i += 4) sum += luminance(Rgb(img.rgba[i], img.rgba[i + 1], img.rgba[i + 2]));
    return sum / double(img.width * img.height);
}

double filmMeanLuminance(const Film& film) {
    double mean[3], se[3];
    test::pixelMean(film, mean, se);
    return luminance(Rgb(float(mean[0]), float(mean[1]), float(mean[2])));
}

}  // namespace

// --radius 0: no merging, every weight is bdpt's and the same random numbers are drawn, so the
// image is bdpt's bit for bit (mirror and glass included: delta vertices on both sub-paths).
TEST(Vcm, WithoutMergingItIsBdptBitForBit) {
    for (const char* name : {"cornell-box", "cornell-box-specular"}) {
        Scene scene = test::loadSourceScene(std::string("scenes/") + name + "/" + name + ".gltf");
        Film vcm = renderVcmTest(scene, VcmIntegrator(PhotonSettings{.radius = 0.f}), 40, 32, 4, 5, 2);
        Film bdpt = renderVcmTest(scene, BdptIntegrator(), 40, 32, 4, 5, 2);
        EXPECT_TRUE(sameBits(vcm, bdpt)) << name;
        EXPECT_GT(filmMeanLuminance(vcm), 0.0) << name;
    }
}

// Closed sphere, uniform emission Le and albedo a: L = Le / (1 − a); a point light at the centre of
// a closed sphere: L = a I / (π R² (1 − a)). Every path is both connected and merged here.
TEST(Vcm, FurnacesWithinOnePercent) {
    Rgb albedo(0.5f, 0.3f, 0.7f), Le(1.f, 2.f, 0.5f);
    for (bool asMesh : {false, true}) {
        Scene scene = test::closedSphere(albedo, Le, asMesh);
        Film film = renderVcmTest(scene, VcmIntegrator(), 32, 32, 64, 99, 2);
        double mean[3], se[3];
        test::pixelMean(film, mean, se);
        Rgb expected = Le / (Rgb(1.f) - albedo);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], expected[c], 0.01 * expected[c]) << (asMesh ? "mesh" : "sphere") << " channel " << c;
    }
    Rgb I(2.f, 1.f, 3.f);
    Scene scene = test::closedSphere(albedo, Rgb(0.f), false, {PointLightDesc{Vec3f(0.1f, -0.2f, 0.05f), I}});
    Film film = renderVcmTest(scene, VcmIntegrator(), 32, 32, 64, 5, 2);
    double mean[3], se[3];
    test::pixelMean(film, mean, se);
    Rgb expected = albedo * I / (kPi * (Rgb(1.f) - albedo));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], expected[c], 0.01 * expected[c]) << "point light channel " << c;
}

// The Cornell box's reference (bdpt, ptnee and Cycles agreeing: refs/README.md): vcm's mean within
// 1% at 32 iterations, and its error no worse than 1.5x bdpt's at equal samples (diffuse paths:
// the connections keep almost all the weight).
TEST(Vcm, CornellBoxAgreesWithTheIndependentReference) {
    Scene scene = test::loadSourceScene("scenes/cornell-box/cornell-box.gltf");
    io::Image ref = test::boxDownsample(io::readImage(test::sourcePath("refs/cornell-box.exr")), 4, false);
    Film vcm = renderVcmTest(scene, VcmIntegrator(), 64, 64, 32, 21, 2);
    Film bdpt = renderVcmTest(scene, BdptIntegrator(), 64, 64, 32, 21, 2);
    double eVcm = lumaRelMseAgainst(vcm, ref), eBdpt = lumaRelMseAgainst(bdpt, ref);
    std::cout << "cornell-box relMSE at 32 spp: vcm " << eVcm << ", bdpt " << eBdpt << "\n";
    EXPECT_LT(eVcm, 1.5 * eBdpt);
    EXPECT_NEAR(filmMeanLuminance(vcm), imageMeanLuminance(ref), 0.01 * imageMeanLuminance(ref));
}

// sds-caustic: light → glass → glass → floor → mirror → eye. bdpt samples it only by a camera path
// hitting the small light through the glass (s = 0); vcm merges it at the floor. At equal samples
// its error against the reference must be a tenth of bdpt's (measured ~1/70 at 256×192).
TEST(Vcm, SdsCausticIsMergedWhereBdptCannotConnect) {
    Scene scene = test::loadSourceScene("scenes/sds-caustic/sds-caustic.gltf");
    io::Image ref = test::boxDownsample(io::readImage(test::sourcePath("refs/sds-caustic.exr")), 4, false);
    ASSERT_EQ(ref.width, 64);
    Film vcm = renderVcmTest(scene, VcmIntegrator(), ref.width, ref.height, 16, 3, 2);
    Film bdpt = renderVcmTest(scene, BdptIntegrator(), ref.width, ref.height, 16, 3, 2);
    double eVcm = lumaRelMseAgainst(vcm, ref), eBdpt = lumaRelMseAgainst(bdpt, ref);
    std::cout << "sds-caustic relMSE at 16 spp: vcm " << eVcm << ", bdpt " << eBdpt << "\n";
    EXPECT_LT(eVcm, 0.1 * eBdpt);
    EXPECT_NEAR(filmMeanLuminance(vcm), imageMeanLuminance(ref), 0.03 * imageMeanLuminance(ref));
}

TEST(Vcm, BitIdenticalForOneAndTwoThreads) {
    Scene scene = test::loadSourceScene("scenes/cornell-box-specular/cornell-box-specular.gltf");
    Film one = renderVcmTest(scene, VcmIntegrator(), 48, 40, 3, 7, 1);
    Film two = renderVcmTest(scene, VcmIntegrator(), 48, 40, 3, 7, 2);
    EXPECT_TRUE(sameBits(one, two));
}
