// The texture layer: image decoding (exact sRGB at 8 bit, float images, limits, corrupt input),
// MIP pyramids, and sampleTexture's wrap modes, filters, footprint-chosen levels and
// KHR_texture_transform.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <fstream>

#include "core/error.h"
#include "test_helpers.h"
#include "texture/texture.h"

namespace tessera {
namespace {

/// Writes `pixels` (row-major, `channels` per pixel) with OpenImageIO to `path` in the format its
/// extension names, and returns the file's bytes.
template <typename T>
std::vector<uint8_t> encodeImage(const std::filesystem::path& path, int width, int height, int channels,
                                 OIIO::TypeDesc type, const std::vector<T>& pixels) {
    auto out = OIIO::ImageOutput::create(path.string());
    EXPECT_TRUE(out) << OIIO::geterror();
    OIIO::ImageSpec spec(width, height, channels, type);
    spec.attribute("oiio:UnassociatedAlpha", 1);  // the pixels hold straight alpha: write them as they are
    EXPECT_TRUE(out->open(path.string(), spec)) << out->geterror();
    EXPECT_TRUE(out->write_image(type, pixels.data())) << out->geterror();
    out->close();
    std::ifstream in(path, std::ios::binary);
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// An in-memory image of one level (plus its pyramid) from a texel function.
Image makeImage(int width, int height, const std::function<Vec4f(int, int)>& texel) {
    Image img;
    img.name = "test";
    img.levels.resize(1);
    img.levels[0].width = width;
    img.levels[0].height = height;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) img.levels[0].texels.push_back(texel(x, y));
    buildMipLevels(img);
    return img;
}

TextureRef textureOf(const Image& img, WrapMode wrap = WrapMode::Repeat, FilterMode filter = FilterMode::Linear) {
    TextureRef t;
    t.image = &img;
    t.wrapS = t.wrapT = wrap;
    t.filter = filter;
    return t;
}

double srgbReference(int code) {
    double v = code / 255.0;
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

TEST(ImageDecode, EightBitSrgbDecodesExactlyAndAlphaStaysLinear) {
    auto dir = test::tempDir("texture-srgb");
    std::vector<uint8_t> pixels;
    for (int i = 0; i < 256; ++i) pixels.insert(pixels.end(), {uint8_t(i), uint8_t(255 - i), uint8_t(i / 2), uint8_t(i)});
    auto bytes = encodeImage(dir / "codes.png", 256, 1, 4, OIIO::TypeDesc::UINT8, pixels);
    Image srgb = decodeImage("codes.png", bytes.data(), bytes.size(), ColorEncoding::Srgb);
    Image linear = decodeImage("codes.png", bytes.data(), bytes.size(), ColorEncoding::Linear);
    ASSERT_EQ(srgb.width(), 256);
    ASSERT_EQ(srgb.height(), 1);
    for (int i = 0; i < 256; ++i) {
        const Vec4f& t = srgb.levels[0].at(i, 0);
        // Exact: the float nearest the double-precision transfer function, for every code.
        EXPECT_EQ(t.r, float(srgbReference(i))) << "code " << i;
        EXPECT_EQ(t.g, float(srgbReference(255 - i))) << "code " << 255 - i;
        EXPECT_EQ(t.b, float(srgbReference(i / 2)));
        EXPECT_FLOAT_EQ(t.a, float(i) / 255.f) << "alpha is linear coverage, never sRGB-decoded";
        EXPECT_FLOAT_EQ(linear.levels[0].at(i, 0).r, float(i) / 255.f);
    }
    // Spot values of the transfer function itself (IEC 61966-2-1): code 128 → 0.21586.
    EXPECT_NEAR(srgb.levels[0].at(128, 0).r, 0.2158605, 1e-6);
    EXPECT_NEAR(srgb.levels[0].at(10, 0).r, 10.0 / 255.0 / 12.92, 1e-9);
}

TEST(ImageDecode, GreyAndGreyAlphaExpandAsGltfSamplesThem) {
    auto dir = test::tempDir("texture-grey");
    std::vector<uint8_t> ga = {51, 255, 204, 0};
    auto bytes = encodeImage(dir / "ga.png", 2, 1, 2, OIIO::TypeDesc::UINT8, ga);
    Image img = decodeImage("ga.png", bytes.data(), bytes.size(), ColorEncoding::Linear);
    EXPECT_EQ(img.levels[0].at(0, 0), Vec4f(0.2f, 0.2f, 0.2f, 1.f));
    EXPECT_EQ(img.levels[0].at(1, 0), Vec4f(0.8f, 0.8f, 0.8f, 0.f));
}

TEST(ImageDecode, FloatExrKeepsValuesAndRowOrder) {
    auto dir = test::tempDir("texture-exr");
    std::vector<float> px = {1.f, 2.f, 3.f, 100.f, 0.5f, 0.25f, -1.f, 0.f, 7.f, 8.f, 9.f, 10.f};
    auto bytes = encodeImage(dir / "f.exr", 2, 2, 3, OIIO::TypeDesc::FLOAT, px);
    Image img = decodeImage("f.exr", bytes.data(), bytes.size(), ColorEncoding::Linear);
    ASSERT_EQ(img.width(), 2);
    EXPECT_EQ(img.levels[0].at(0, 0), Vec4f(1.f, 2.f, 3.f, 1.f));   // row 0 is the top row
    EXPECT_EQ(img.levels[0].at(1, 0), Vec4f(100.f, 0.5f, 0.25f, 1.f));
    EXPECT_EQ(img.levels[0].at(0, 1), Vec4f(-1.f, 0.f, 7.f, 1.f));
    // Pyramid: 2x2 → 1x1, the mean.
    ASSERT_EQ(img.levels.size(), 2u);
    EXPECT_FLOAT_EQ(img.levels[1].at(0, 0).r, (1.f + 100.f - 1.f + 8.f) / 4.f);
}

TEST(ImageDecode, JpegAndRadianceHdrDecodeFromMemory) {
    auto dir = test::tempDir("texture-formats");
    std::vector<uint8_t> grey(16 * 16 * 3, 200);
    auto jpg = encodeImage(dir / "g.jpg", 16, 16, 3, OIIO::TypeDesc::UINT8, grey);
    Image j = decodeImage("g.jpg", jpg.data(), jpg.size(), ColorEncoding::Linear);
    EXPECT_NEAR(j.levels[0].at(7, 7).g, 200.f / 255.f, 2.f / 255.f);  // lossy, but a flat image survives
    std::vector<float> hdr = {0.25f, 1.f, 4.f, 1000.f, 0.5f, 0.125f};
    auto rgbe = encodeImage(dir / "e.hdr", 2, 1, 3, OIIO::TypeDesc::FLOAT, hdr);
    Image h = decodeImage("e.hdr", rgbe.data(), rgbe.size(), ColorEncoding::Linear);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(h.levels[0].at(0, 0)[c], hdr[size_t(c)], 0.01f * hdr[0 + 2]);  // RGBE: 8 bits of mantissa
        EXPECT_NEAR(h.levels[0].at(1, 0)[c], hdr[size_t(3 + c)], 0.01f * 1000.f);
    }
}

TEST(ImageDecode, RefusesCorruptTruncatedAndOversizedImagesNamingThem) {
    auto dir = test::tempDir("texture-bad");
    std::vector<uint8_t> px(64 * 64 * 3, 128);
    auto png = encodeImage(dir / "ok.png", 64, 64, 3, OIIO::TypeDesc::UINT8, px);
    auto message = [](const std::function<void()>& f) {
        try {
            f();
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    std::vector<uint8_t> junk = {'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd'};
    EXPECT_EQ(message([&] { decodeImage("images[0] (a.png)", junk.data(), junk.size(), ColorEncoding::Srgb); }),
              "images[0] (a.png): not a PNG, JPEG, OpenEXR or Radiance HDR image");
    std::vector<uint8_t> truncated(png.begin(), png.begin() + std::ptrdiff_t(png.size() / 2));
    EXPECT_NE(message([&] { decodeImage("t.png", truncated.data(), truncated.size(), ColorEncoding::Srgb); })
                  .find("t.png: cannot decode png image"),
              std::string::npos);
    ImageDecodeLimits small;
    small.maxPixels = 1000;  // 64 × 64 = 4096 pixels
    EXPECT_NE(message([&] { decodeImage("big.png", png.data(), png.size(), ColorEncoding::Srgb, small); })
                  .find("big.png: image of 64x64 pixels is over the limit"),
              std::string::npos);
    EXPECT_EQ(message([&] { decodeImage("e.png", png.data(), 0, ColorEncoding::Srgb); }), "e.png: image is empty");
    EXPECT_EQ(message([&] { readImageFile((dir / "missing.png").string(), ColorEncoding::Srgb); }),
              (dir / "missing.png").string() + ": no such file");
    // The good image still decodes, through the file path too.
    EXPECT_EQ(readImageFile((dir / "ok.png").string(), ColorEncoding::Linear).width(), 64);
}

TEST(Mip, PyramidOfOddSizesConservesTheMean) {
    Image img = makeImage(5, 3, [](int x, int y) { return Vec4f(float(x * 7 + y * 3 % 5), float(y), 1.f, 0.5f); });
    double mean0 = 0.0;
    for (const Vec4f& t : img.levels[0].texels) mean0 += t.r;
    mean0 /= double(img.levels[0].texels.size());
    ASSERT_EQ(img.levels.size(), 3u);  // 5x3 → 2x1 → 1x1
    EXPECT_EQ(img.levels[1].width, 2);
    EXPECT_EQ(img.levels[1].height, 1);
    EXPECT_NEAR(img.levels.back().at(0, 0).r, mean0, 1e-5);
    EXPECT_FLOAT_EQ(img.levels.back().at(0, 0).b, 1.f);
}

TEST(SampleTexture, TexelCentresReturnTexelsExactlyInBothFilters) {
    Image img = makeImage(8, 4, [](int x, int y) { return Vec4f(float(x), float(y), float((x + y) % 2), 1.f); });
    for (FilterMode f : {FilterMode::Nearest, FilterMode::Linear}) {
        TextureRef tex = textureOf(img, WrapMode::Repeat, f);
        for (int y = 0; y < 4; ++y)
            for (int x = 0; x < 8; ++x) {
                Vec2f uv((x + 0.5f) / 8.f, (y + 0.5f) / 4.f);
                EXPECT_EQ(sampleTexture(tex, uv, 0.f), img.levels[0].at(x, y)) << x << "," << y;
            }
    }
    // Bilinear halfway between two centres is their mean; nearest picks the texel containing uv.
    TextureRef lin = textureOf(img, WrapMode::ClampToEdge, FilterMode::Linear);
    EXPECT_FLOAT_EQ(sampleTexture(lin, Vec2f(2.f / 8.f, 0.5f / 4.f), 0.f).r, 1.5f);
    TextureRef near = textureOf(img, WrapMode::ClampToEdge, FilterMode::Nearest);
    EXPECT_EQ(sampleTexture(near, Vec2f(2.01f / 8.f, 0.5f / 4.f), 0.f).r, 2.f);
    EXPECT_EQ(sampleTexture(near, Vec2f(1.99f / 8.f, 0.5f / 4.f), 0.f).r, 1.f);
}

TEST(SampleTexture, WrapModes) {
    Image img = makeImage(4, 1, [](int x, int) { return Vec4f(float(x), 0.f, 0.f, 1.f); });
    auto at = [&](WrapMode m, float u) { return sampleTexture(textureOf(img, m, FilterMode::Nearest), Vec2f(u, 0.5f), 0.f).r; };
    // Repeat: period 1.
    EXPECT_EQ(at(WrapMode::Repeat, 1.125f), 0.f);
    EXPECT_EQ(at(WrapMode::Repeat, 1.875f), 3.f);
    EXPECT_EQ(at(WrapMode::Repeat, -0.125f), 3.f);
    EXPECT_EQ(at(WrapMode::Repeat, 1500000.375f), at(WrapMode::Repeat, 0.375f));
    // Mirrored repeat: [1, 2) is [0, 1) reversed, [−1, 0) too.
    EXPECT_EQ(at(WrapMode::MirroredRepeat, 1.125f), 3.f);
    EXPECT_EQ(at(WrapMode::MirroredRepeat, 1.875f), 0.f);
    EXPECT_EQ(at(WrapMode::MirroredRepeat, -0.125f), 0.f);
    EXPECT_EQ(at(WrapMode::MirroredRepeat, 2.125f), 0.f);
    // Clamp to edge.
    EXPECT_EQ(at(WrapMode::ClampToEdge, 1.5f), 3.f);
    EXPECT_EQ(at(WrapMode::ClampToEdge, -7.f), 0.f);
    // Bilinear across the seam: repeat blends texel 3 with texel 0, clamp stays on texel 3.
    auto lin = [&](WrapMode m, float u) { return sampleTexture(textureOf(img, m, FilterMode::Linear), Vec2f(u, 0.5f), 0.f).r; };
    EXPECT_FLOAT_EQ(lin(WrapMode::Repeat, 1.f), 1.5f);
    EXPECT_FLOAT_EQ(lin(WrapMode::ClampToEdge, 1.f), 3.f);
    // Non-finite coordinates never reach the lookup.
    EXPECT_TRUE(std::isfinite(lin(WrapMode::Repeat, std::nanf(""))));
}

TEST(SampleTexture, FootprintSelectsAndBlendsMipLevels) {
    // 1-texel checkerboard: level 0 alternates 0/1; every coarser level is 0.5.
    Image img = makeImage(64, 64, [](int x, int y) { return Vec4f(float((x + y) % 2), 0.f, 0.f, 1.f); });
    TextureRef tex = textureOf(img);
    Vec2f uv(0.5f / 64.f, 0.5f / 64.f);  // the centre of texel (0, 0) = 0
    EXPECT_EQ(sampleTexture(tex, uv, 0.f).r, 0.f);
    EXPECT_EQ(sampleTexture(tex, uv, 1.f / 64.f).r, 0.f);          // one texel wide: level 0
    EXPECT_FLOAT_EQ(sampleTexture(tex, uv, 2.f / 64.f).r, 0.5f);   // two texels: level 1
    EXPECT_FLOAT_EQ(sampleTexture(tex, uv, 1.f).r, 0.5f);          // the whole texture: level 6
    float between = sampleTexture(tex, uv, std::sqrt(2.f) / 64.f).r;  // λ = ½: halfway
    EXPECT_NEAR(between, 0.25f, 1e-6f);
    // KHR_texture_transform's scale widens the footprint in texture space: 1 texel of the mesh's uv
    // is 2 texels after a scale of 2, so level 1.
    tex.transform.scale = Vec2f(2.f, 2.f);
    EXPECT_FLOAT_EQ(sampleTexture(tex, uv * 0.5f, 1.f / 64.f).r, 0.5f);
    tex.transform.scale = Vec2f(0.5f, 0.5f);
    EXPECT_EQ(sampleTexture(tex, uv * 2.f, 2.f / 64.f).r, 0.f);
}

TEST(SampleTexture, KhrTextureTransformFollowsTheExtensionsExample) {
    // KHR_texture_transform's example: offset [0, 1], rotation π/2, scale [½, ½] "utilizes only the
    // lower left quadrant of the source image, rotated clockwise 90°".
    TextureTransform t;
    t.offset = Vec2f(0.f, 1.f);
    t.rotation = 1.57079632679f;
    t.scale = Vec2f(0.5f);
    auto near = [](Vec2f a, Vec2f b) { return std::abs(a.x - b.x) < 1e-6f && std::abs(a.y - b.y) < 1e-6f; };
    EXPECT_TRUE(near(t.apply(Vec2f(0.f, 0.f)), Vec2f(0.f, 1.f)));
    EXPECT_TRUE(near(t.apply(Vec2f(1.f, 0.f)), Vec2f(0.f, 0.5f)));
    EXPECT_TRUE(near(t.apply(Vec2f(0.f, 1.f)), Vec2f(0.5f, 1.f)));
    EXPECT_TRUE(near(t.apply(Vec2f(1.f, 1.f)), Vec2f(0.5f, 0.5f)));
    // "Inverts the T axis": offset [0, 1], scale [1, −1].
    TextureTransform flip;
    flip.offset = Vec2f(0.f, 1.f);
    flip.scale = Vec2f(1.f, -1.f);
    EXPECT_TRUE(near(flip.apply(Vec2f(0.25f, 0.f)), Vec2f(0.25f, 1.f)));
    // sampleTexture applies it before wrapping.
    Image img = makeImage(2, 2, [](int x, int y) { return Vec4f(float(x + 2 * y), 0.f, 0.f, 1.f); });
    TextureRef tex = textureOf(img, WrapMode::Repeat, FilterMode::Nearest);
    tex.transform = flip;
    EXPECT_EQ(sampleTexture(tex, Vec2f(0.25f, 0.25f), 0.f).r, 2.f);  // v 0.25 → 0.75: the bottom row
}

}  // namespace
}  // namespace tessera
