// EXR/PNG output: round trip with metadata, atomic writes, the display transform, image comparison.
#include <gtest/gtest.h>

#include <fstream>

#include "core/error.h"
#include "io/display_transform.h"
#include "io/image_compare.h"
#include "io/image_output.h"
#include "test_helpers.h"

using namespace tessera;

namespace {
std::vector<float> gradient(int w, int h) {
    std::vector<float> px(size_t(w) * h * 4);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float* p = &px[(size_t(y) * w + x) * 4];
            p[0] = float(x) / w * 4.f;
            p[1] = float(y) / h;
            p[2] = 0.25f;
            p[3] = 1.f;
        }
    return px;
}
}  // namespace

TEST(ImageIo, ExrRoundTripKeepsPixelsAndMetadata) {
    auto dir = test::tempDir("io-roundtrip");
    std::vector<float> px = gradient(37, 21);
    std::string path = (dir / "sub" / "img.exr").string();
    io::writeExr(path, 37, 21, px.data(), {{"tessera:spp", "64"}, {"tessera:integrator", "ptnee"}});
    io::Image img = io::readImage(path);
    ASSERT_EQ(img.width, 37);
    ASSERT_EQ(img.height, 21);
    EXPECT_EQ(img.rgba, px);
    bool found = false;
    for (auto& [k, v] : img.metadata) found |= (k == "tessera:spp" && v == "64");
    EXPECT_TRUE(found);
    for (auto& e : std::filesystem::directory_iterator(dir / "sub"))
        EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

TEST(ImageIo, FailedWriteLeavesTheOldFileAlone) {
    auto dir = test::tempDir("io-atomic");
    std::string path = (dir / "keep.exr").string();
    std::vector<float> px = gradient(8, 8);
    io::writeExr(path, 8, 8, px.data(), {});
    auto before = std::filesystem::file_size(path);
    // The parent of this destination is a regular file: the write must fail cleanly.
    EXPECT_THROW(io::writeExr(path + "/inside.exr", 8, 8, px.data(), {}), InputError);
    EXPECT_EQ(std::filesystem::file_size(path), before);
    int files = 0;
    for (auto& e : std::filesystem::directory_iterator(dir)) (void)e, ++files;
    EXPECT_EQ(files, 1);
}

TEST(ImageIo, StandardViewIsTheSrgbCurve) {
    io::DisplayTransform t("sRGB", "Standard");
    float px[8] = {0.18f, 0.f, 1.f, 0.5f, 2.f, 0.0031308f, 0.5f, 1.f};
    t.apply(px, 2, 1);
    EXPECT_NEAR(px[0], 0.4613561f, 1e-4f);
    EXPECT_NEAR(px[1], 0.f, 1e-6f);
    EXPECT_NEAR(px[2], 1.f, 1e-4f);
    EXPECT_EQ(px[3], 0.5f);  // alpha untouched
    EXPECT_NEAR(px[5], 0.04045f, 1e-4f);
    EXPECT_THROW(io::DisplayTransform("sRGB", "NoSuchView"), InputError);
    io::DisplayTransform aces("sRGB", "ACES 1.0 SDR-video");
    float grey[4] = {0.18f, 0.18f, 0.18f, 1.f};
    aces.apply(grey, 1, 1);
    EXPECT_GT(grey[0], 0.2f);
    EXPECT_LT(grey[0], 0.5f);
}

TEST(ImageIo, CompareMeasuresKnownErrors) {
    auto dir = test::tempDir("io-compare");
    std::vector<float> ref = gradient(16, 8), test = ref;
    test[(3 * 16 + 5) * 4 + 1] += 0.5f;  // one green error at (5, 3)
    test[(7 * 16 + 0) * 4 + 0] = std::numeric_limits<float>::quiet_NaN();
    io::writeExr((dir / "ref.exr").string(), 16, 8, ref.data(), {});
    io::writeExr((dir / "test.exr").string(), 16, 8, test.data(), {});
    io::CompareResult same = io::compareImages((dir / "ref.exr").string(), (dir / "ref.exr").string());
    EXPECT_EQ(same.rmse, 0.0);
    EXPECT_EQ(same.relMse, 0.0);
    io::CompareResult r = io::compareImages((dir / "test.exr").string(), (dir / "ref.exr").string());
    EXPECT_EQ(r.nonFiniteTest, 1);
    EXPECT_EQ(r.nonFiniteRef, 0);
    EXPECT_NEAR(r.maxAbsError, 0.5, 1e-6);
    EXPECT_EQ(r.maxX, 5);
    EXPECT_EQ(r.maxY, 3);
    double refG = ref[(3 * 16 + 5) * 4 + 1];
    EXPECT_NEAR(r.relMse, 0.25 / (refG * refG + 0.01) / (127.0 * 3.0), 1e-9);
    EXPECT_NEAR(r.rmse, std::sqrt(0.25 / (127.0 * 3.0)), 1e-9);
}
