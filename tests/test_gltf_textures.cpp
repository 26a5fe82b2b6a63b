// The texture half of the glTF loader: texture-coordinate formats, samplers and
// KHR_texture_transform, colour vs data encodings, the three places an image can live, tangents
// from the file vs generated, alpha modes, and the image memory budget.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "gltf_test_files.h"
#include "scene/gltf_loader.h"
#include "test_helpers.h"

using namespace tessera;
using test::GltfBuilder;
using test::pngBytes;

namespace {

/// A unit quad facing +z (two triangles) with TEXCOORD_0 = ((x + 1)/2, (1 − y)/2); returns the
/// primitive object to add to a mesh.
nlohmann::json quadPrimitive(GltfBuilder& b, int material = -1) {
    nlohmann::json prim = {{"attributes",
                            {{"POSITION", b.positions({-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0})},
                             {"NORMAL", b.floats({0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}, 3, "VEC3")},
                             {"TEXCOORD_0", b.floats({0, 1, 1, 1, 1, 0, 0, 0}, 2, "VEC2")}}},
                           {"indices", b.indices({0, 1, 2, 0, 2, 3})}};
    if (material >= 0) prim["material"] = material;
    return prim;
}

void addMeshNode(GltfBuilder& b, const nlohmann::json& prim, const nlohmann::json& node = nlohmann::json::object()) {
    b.doc["meshes"].push_back({{"primitives", {prim}}});
    nlohmann::json n = node;
    n["mesh"] = b.doc["meshes"].size() - 1;
    b.doc["nodes"].push_back(n);
    b.doc["scenes"] = {{{"nodes", nlohmann::json::array()}}};
    for (size_t i = 0; i < b.doc["nodes"].size(); ++i) b.doc["scenes"][0]["nodes"].push_back(i);
    b.doc["scene"] = 0;
}

Scene load(const std::string& path, std::vector<std::string>* warningsOut = nullptr, const SceneLoadOptions& options = {}) {
    std::vector<std::string> warnings;
    Scene s = loadGltfScene(path, warnings, options);
    if (warningsOut) *warningsOut = warnings;
    return s;
}

/// 4×2 RGBA test pixels with distinct codes in every channel.
std::vector<uint8_t> testPixels() {
    std::vector<uint8_t> px;
    for (int i = 0; i < 8; ++i)
        for (int c = 0; c < 4; ++c) px.push_back(uint8_t((i * 37 + c * 61 + 11) % 256));
    return px;
}

float srgbToLinear(uint8_t code) {
    double v = code / 255.0;
    return float(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
}

}  // namespace

TEST(GltfTextures, TexcoordFormatsAreReadAsTheSpecDefines) {
    auto dir = test::tempDir("gltf-texcoords");
    GltfBuilder b;
    nlohmann::json prim = quadPrimitive(b);
    std::vector<uint8_t> u8 = {0, 255, 128, 51, 1, 2, 3, 4};
    std::vector<uint16_t> u16 = {0, 65535, 32768, 13107, 7, 8, 9, 10};
    prim["attributes"]["TEXCOORD_0"] = b.accessor(GltfBuilder::bytesOf(u8), 4, 5121, "VEC2", true);
    prim["attributes"]["TEXCOORD_1"] = b.accessor(GltfBuilder::bytesOf(u16), 4, 5123, "VEC2", true);
    addMeshNode(b, prim);
    b.write((dir / "t.gltf").string());
    Scene s = load((dir / "t.gltf").string());
    ASSERT_EQ(s.geometry.meshes.size(), 1u);
    const TriangleMesh& m = s.geometry.meshes[0];
    ASSERT_EQ(m.texcoords[0].size(), 4u);
    ASSERT_EQ(m.texcoords[1].size(), 4u);
    for (size_t i = 0; i < 4; ++i)
        for (int c = 0; c < 2; ++c) {
            EXPECT_EQ(m.texcoords[0][i][c], u8[2 * i + size_t(c)] / 255.f) << i;
            EXPECT_EQ(m.texcoords[1][i][c], u16[2 * i + size_t(c)] / 65535.f) << i;
        }
    // The interpolation the renderer uses sees them: vertex 1 of triangle 0 is (128, 51)/255.
    EXPECT_EQ(m.texcoordAt(0, 0, 1.f, 0.f), Vec2f(128 / 255.f, 51 / 255.f));
}

TEST(GltfTextures, SamplerAndTextureTransformAreParsed) {
    auto dir = test::tempDir("gltf-sampler");
    GltfBuilder b;
    nlohmann::json prim = quadPrimitive(b, 0);
    prim["attributes"]["TEXCOORD_1"] = b.floats({0, 0, 1, 0, 1, 1, 0, 1}, 2, "VEC2");
    addMeshNode(b, prim);
    int image = b.image(pngBytes(4, 2, 4, testPixels()), false);
    b.doc["samplers"] = {{{"magFilter", 9728}, {"minFilter", 9987}, {"wrapS", 33648}, {"wrapT", 33071}}};
    int sampled = b.texture(image, 0), plain = b.texture(image);
    b.doc["materials"] = {
        {{"pbrMetallicRoughness",
          {{"baseColorTexture",
            {{"index", sampled},
             {"extensions", {{"KHR_texture_transform", {{"offset", {0.25, -0.5}}, {"rotation", 0.3}, {"scale", {2, 3}}, {"texCoord", 1}}}}}}},
           {"metallicRoughnessTexture", {{"index", plain}}}}}}};
    b.doc["extensionsUsed"] = {"KHR_texture_transform"};
    b.doc["extensionsRequired"] = {"KHR_texture_transform"};
    b.write((dir / "s.gltf").string());
    Scene s = load((dir / "s.gltf").string());
    const MaterialTextures& t = s.materials[0].textures;
    ASSERT_TRUE(t.baseColor.valid());
    EXPECT_EQ(t.baseColor.texCoord, 1);  // the transform's texCoord overrides the textureInfo's
    EXPECT_EQ(t.baseColor.transform.offset, Vec2f(0.25f, -0.5f));
    EXPECT_EQ(t.baseColor.transform.scale, Vec2f(2.f, 3.f));
    EXPECT_EQ(t.baseColor.transform.rotation, 0.3f);
    EXPECT_EQ(t.baseColor.wrapS, WrapMode::MirroredRepeat);
    EXPECT_EQ(t.baseColor.wrapT, WrapMode::ClampToEdge);
    EXPECT_EQ(t.baseColor.filter, FilterMode::Nearest);
    ASSERT_TRUE(t.metallicRoughness.valid());  // no sampler: glTF's defaults
    EXPECT_EQ(t.metallicRoughness.texCoord, 0);
    EXPECT_TRUE(t.metallicRoughness.transform.identity());
    EXPECT_EQ(t.metallicRoughness.wrapS, WrapMode::Repeat);
    EXPECT_EQ(t.metallicRoughness.wrapT, WrapMode::Repeat);
    EXPECT_EQ(t.metallicRoughness.filter, FilterMode::Linear);
}

// Colour slots (baseColor, emissive, specularColor) decode sRGB, data slots linear; each image is
// decoded once per encoding however many slots use it. Alpha is linear in both.
TEST(GltfTextures, ColourSlotsDecodeSrgbDataSlotsLinearOncePerEncoding) {
    auto dir = test::tempDir("gltf-encodings");
    GltfBuilder b;
    addMeshNode(b, quadPrimitive(b, 0));
    std::vector<uint8_t> px = testPixels();
    int tex = b.texture(b.image(pngBytes(4, 2, 4, px), true));
    b.doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", tex}}}, {"metallicRoughnessTexture", {{"index", tex}}}}},
                           {"normalTexture", {{"index", tex}, {"scale", 0.5}}},
                           {"emissiveTexture", {{"index", tex}}},
                           {"emissiveFactor", {1, 1, 1}},
                           {"extensions",
                            {{"KHR_materials_specular", {{"specularTexture", {{"index", tex}}}, {"specularColorTexture", {{"index", tex}}}}},
                             {"KHR_materials_transmission", {{"transmissionTexture", {{"index", tex}}}}}}}}};
    b.write((dir / "e.glb").string());
    Scene s = load((dir / "e.glb").string());
    const MaterialTextures& t = s.materials[0].textures;
    EXPECT_EQ(s.images.size(), 2u);
    EXPECT_EQ(t.baseColor.image, t.emissive.image);
    EXPECT_EQ(t.baseColor.image, t.specularColor.image);
    EXPECT_EQ(t.metallicRoughness.image, t.normal.image);
    EXPECT_EQ(t.metallicRoughness.image, t.specular.image);
    EXPECT_EQ(t.metallicRoughness.image, t.transmission.image);
    EXPECT_NE(t.baseColor.image, t.metallicRoughness.image);
    EXPECT_EQ(t.normalScale, 0.5f);
    for (int i = 0; i < 8; ++i) {
        const Vec4f& srgb = t.baseColor.image->levels[0].at(i % 4, i / 4);
        const Vec4f& linear = t.metallicRoughness.image->levels[0].at(i % 4, i / 4);
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(srgb[c], srgbToLinear(px[size_t(4 * i + c)])) << i << " " << c;
            EXPECT_NEAR(linear[c], px[size_t(4 * i + c)] / 255.f, 1e-7f) << i << " " << c;
        }
        EXPECT_NEAR(srgb.a, px[size_t(4 * i + 3)] / 255.f, 1e-7f);
        EXPECT_NEAR(linear.a, px[size_t(4 * i + 3)] / 255.f, 1e-7f);
    }
}

TEST(GltfTextures, GlbViewDataUriAndFileImagesDecodeAlike) {
    auto dir = test::tempDir("gltf-image-places");
    std::string png = pngBytes(4, 2, 4, testPixels());
    std::ofstream(dir / "image.png", std::ios::binary) << png;
    GltfBuilder b;
    addMeshNode(b, quadPrimitive(b, 0));
    int view = b.texture(b.image(png, true)), uri = b.texture(b.image(png, false)), file = b.texture(b.imageFile("image.png"));
    b.doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", view}}}}},
                           {"emissiveTexture", {{"index", uri}}},
                           {"extensions", {{"KHR_materials_specular", {{"specularColorTexture", {{"index", file}}}}}}}}};
    b.write((dir / "p.gltf").string());
    Scene s = load((dir / "p.gltf").string());
    ASSERT_EQ(s.images.size(), 3u);
    for (size_t i = 1; i < 3; ++i) {
        ASSERT_EQ(s.images[i]->width(), 4);
        ASSERT_EQ(s.images[i]->height(), 2);
        EXPECT_EQ(s.images[i]->levels[0].texels, s.images[0]->levels[0].texels) << i;
    }
}

// On a planar grid whose uv is a rotation and anisotropic scale of its position, the tangent is
// known exactly, and the file's TANGENT is what an exporter's MikkTSpace writes (w = −1: the map
// preserves orientation in glTF's v-down uv, so B = w · N × T points up the image, along −∂p/∂v).
// Generated tangents must equal the file's; under a mirroring node transform the bitangent must
// still point along the world-space −∂p/∂v, for both.
TEST(GltfTextures, GeneratedTangentsMatchTheFilesTangents) {
    auto dir = test::tempDir("gltf-tangents");
    const int n = 5;
    const float theta = 0.6f, su = 1.5f, sv = 0.75f, c = std::cos(theta), s = std::sin(theta);
    std::vector<float> pos, nrm, uv, tan;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            float x = float(i) / n, y = float(j) / n;
            pos.insert(pos.end(), {x, y, 0.f});
            nrm.insert(nrm.end(), {0.f, 0.f, 1.f});
            uv.insert(uv.end(), {su * (c * x - s * y), sv * (s * x + c * y)});
            Vec3f t = glm::normalize(Vec3f(c, -s, 0.f));  // ∂p/∂u = Rᵀ (1/su, 0)
            tan.insert(tan.end(), {t.x, t.y, t.z, -1.f});
        }
    std::vector<uint32_t> ix;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            uint32_t a = uint32_t(j * (n + 1) + i);
            ix.insert(ix.end(), {a, a + 1, a + uint32_t(n) + 2, a, a + uint32_t(n) + 2, a + uint32_t(n) + 1});
        }
    std::vector<uint8_t> flat = {128, 128, 255, 255};
    for (bool mirrored : {false, true}) {
        std::vector<Vec4f> tangents[2];
        for (int withFile = 0; withFile < 2; ++withFile) {
            GltfBuilder b;
            nlohmann::json prim = {{"attributes", {{"POSITION", b.positions(pos)}, {"NORMAL", b.floats(nrm, 3, "VEC3")}, {"TEXCOORD_0", b.floats(uv, 2, "VEC2")}}},
                                   {"indices", b.indices(ix)},
                                   {"material", 0}};
            if (withFile) prim["attributes"]["TANGENT"] = b.floats(tan, 4, "VEC4");
            nlohmann::json node = nlohmann::json::object();
            if (mirrored) node["scale"] = {-1, 1, 1};
            addMeshNode(b, prim, node);
            b.doc["materials"] = {{{"normalTexture", {{"index", b.texture(b.image(pngBytes(1, 1, 4, flat), true))}}}}};
            std::string name = "g";  // appended piecewise: GCC 12 flags "literal" + string&& (-Wrestrict false positive)
            name += std::to_string(mirrored) + std::to_string(withFile) + ".glb";
            std::string path = (dir / name).string();
            b.write(path);
            Scene sc = load(path);
            ASSERT_EQ(sc.geometry.meshes.size(), 1u);
            const TriangleMesh& m = sc.geometry.meshes[0];
            ASSERT_EQ(m.tangents.size(), m.positions.size());
            tangents[withFile] = m.tangents;
            // World ∂p/∂v: Rᵀ (0, 1/sv) = (s, c) / sv, with x negated by the mirror.
            Vec3f dpdv = glm::normalize(Vec3f(mirrored ? -s : s, c, 0.f));
            for (size_t v = 0; v < m.tangents.size(); ++v) {
                Vec3f bitangent = m.tangents[v].w * glm::cross(m.normals[v], Vec3f(m.tangents[v]));
                EXPECT_GT(glm::dot(bitangent, -dpdv), 0.999f) << "mirrored " << mirrored << " file " << withFile << " vertex " << v;
            }
        }
        ASSERT_EQ(tangents[0].size(), tangents[1].size());
        for (size_t v = 0; v < tangents[0].size(); ++v)
            for (int k = 0; k < 4; ++k) EXPECT_NEAR(tangents[0][v][k], tangents[1][v][k], 1e-5f) << "mirrored " << mirrored << " vertex " << v;
    }
}

TEST(GltfTextures, AlphaModesBecomeSharedMasks) {
    auto dir = test::tempDir("gltf-alpha");
    GltfBuilder b;
    int tex = b.texture(b.image(pngBytes(4, 2, 4, testPixels()), true));
    nlohmann::json pbr = {{"baseColorTexture", {{"index", tex}}}, {"baseColorFactor", {1, 1, 1, 0.8}}};
    b.doc["materials"] = {{{"pbrMetallicRoughness", pbr}},                                                    // OPAQUE
                          {{"pbrMetallicRoughness", pbr}, {"alphaMode", "MASK"}, {"alphaCutoff", 0.3}},      // cut-out
                          {{"pbrMetallicRoughness", pbr}, {"alphaMode", "BLEND"}, {"name", "glass"}},        // as MASK 0.5
                          {{"pbrMetallicRoughness", {{"baseColorFactor", {1, 1, 1, 0.9}}}}, {"alphaMode", "MASK"}}};  // keeps all
    for (int mat = 0; mat < 4; ++mat) addMeshNode(b, quadPrimitive(b, mat));
    addMeshNode(b, quadPrimitive(b, 1));
    b.write((dir / "a.glb").string());
    std::vector<std::string> warnings;
    Scene s = load((dir / "a.glb").string(), &warnings);
    ASSERT_EQ(s.geometry.meshes.size(), 5u);
    EXPECT_EQ(s.geometry.meshes[0].alphaMask, nullptr);
    ASSERT_NE(s.geometry.meshes[1].alphaMask, nullptr);
    EXPECT_EQ(s.geometry.meshes[1].alphaMask->cutoff, 0.3f);
    EXPECT_EQ(s.geometry.meshes[1].alphaMask->factor, 0.8f);
    EXPECT_EQ(s.geometry.meshes[1].alphaMask->texture.image, s.materials[1].textures.baseColor.image);
    EXPECT_EQ(s.geometry.meshes[4].alphaMask, s.geometry.meshes[1].alphaMask);  // one mask per material
    ASSERT_NE(s.geometry.meshes[2].alphaMask, nullptr);
    EXPECT_EQ(s.geometry.meshes[2].alphaMask->cutoff, 0.5f);
    EXPECT_EQ(s.materials[2].alphaMode, AlphaMode::Blend);
    EXPECT_EQ(s.geometry.meshes[3].alphaMask, nullptr);
    int blendWarnings = 0;
    for (const std::string& w : warnings) blendWarnings += w.find("BLEND is rendered as MASK with alphaCutoff 0.5") != std::string::npos;
    EXPECT_EQ(blendWarnings, 1);
}

// Decoded images together stay under --max-memory (SceneLoadOptions::maxFileBytes).
TEST(GltfTextures, DecodedImagesStayUnderTheMemoryLimit) {
    auto dir = test::tempDir("gltf-image-budget");
    GltfBuilder b;
    addMeshNode(b, quadPrimitive(b, 0));
    std::vector<uint8_t> big(32 * 32 * 4, 200);  // 32 × 32 RGBA float with MIP levels ≈ 21.8 kB decoded
    b.doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", b.texture(b.image(pngBytes(32, 32, 4, big), true))}}}}}}};
    b.write((dir / "m.glb").string());
    SceneLoadOptions options;
    options.maxFileBytes = 16 << 10;
    try {
        load((dir / "m.glb").string(), nullptr, options);
        FAIL() << "a 22 kB image loaded under a 16 kB limit";
    } catch (const SceneError& e) {
        std::string what = e.what();
        EXPECT_NE(what.find("materials[0].pbrMetallicRoughness.baseColorTexture"), std::string::npos) << what;
        EXPECT_NE(what.find("over the limit"), std::string::npos) << what;
        EXPECT_NE(what.find("--max-memory"), std::string::npos) << what;
    }
    options.maxFileBytes = 64 << 10;
    EXPECT_EQ(load((dir / "m.glb").string(), nullptr, options).images.size(), 1u);
}
