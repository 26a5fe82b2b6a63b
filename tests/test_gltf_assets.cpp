// glTF files from elsewhere: unsupported extensions are named (an error when required, one warning
// line when only used), KHR_mesh_quantization's integer attributes are read, TESSERA_asset_gltf
// imports an asset under its node, every WebXR controller model of the fetched
// @webxr-input-profiles/assets package loads (the load survey), and the fetched HDRIs decode.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <iostream>

#include "core/error.h"
#include "scene/gltf_loader.h"
#include "test_helpers.h"
#include "texture/image.h"

using namespace tessera;
namespace fs = std::filesystem;

namespace {

/// One triangle (0,0,0), (1,0,0), (0,1,0) facing +z, in `bin` (positions then uint32 indices),
/// with `extra` spliced into the root object and `primExtra` into the primitive.
std::string triangleGltf(const std::string& bin, const std::string& extra = "", const std::string& primExtra = "",
                         const std::string& nodes = R"([{"mesh": 0}])") {
    return R"({"asset": {"version": "2.0"}, )" + extra + R"("scene": 0, "scenes": [{"nodes": [0]}],
      "nodes": )" + nodes + R"(,
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0)" + primExtra + R"(}]}],
      "materials": [{"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1], "metallicFactor": 0}}],
      "buffers": [{"byteLength": 48, "uri": ")" + bin + R"("}],
      "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 12}],
      "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
                    {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}]})";
}

void writeFile(const fs::path& path, const void* data, size_t size) {
    fs::create_directories(path.parent_path());
    std::ofstream out(path, std::ios::binary);
    out.write(static_cast<const char*>(data), std::streamsize(size));
}

void writeText(const fs::path& path, const std::string& text) { writeFile(path, text.data(), text.size()); }

/// The triangle's buffer (48 bytes) as `name` in `dir`.
void writeTriangleBin(const fs::path& dir, const std::string& name) {
    const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t ix[3] = {0, 1, 2};
    unsigned char bytes[48];
    std::memcpy(bytes, p, 36);
    std::memcpy(bytes + 36, ix, 12);
    writeFile(dir / name, bytes, 48);
}

struct Loaded {
    std::string error;  ///< "" when it loaded
    std::vector<std::string> warnings;
};

Loaded tryLoad(const fs::path& path, const std::vector<std::string>& assetRoots = {}) {
    Loaded r;
    SceneLoadOptions options;
    options.assetRoots = assetRoots;
    try {
        loadGltfScene(path.string(), r.warnings, options);
    } catch (const SceneError& e) {
        r.error = e.what();
    }
    return r;
}

size_t countContaining(const std::vector<std::string>& lines, const std::string& text) {
    return size_t(std::count_if(lines.begin(), lines.end(), [&](const std::string& l) { return l.find(text) != std::string::npos; }));
}

}  // namespace

TEST(GltfExtensions, UsedButUnsupportedGivesOneWarningLineEach) {
    fs::path dir = test::tempDir("ext-used");
    writeTriangleBin(dir, "t.bin");
    // Two materials use KHR_materials_clearcoat: still one line for it; a supported one gives none.
    std::string text = triangleGltf("t.bin", R"("extensionsUsed": ["EXT_magic", "KHR_materials_clearcoat", "KHR_materials_ior"], )");
    text.replace(text.find(R"("materials": [)"), std::strlen(R"("materials": [)"),
                 R"("materials": [{"name": "c1", "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1}}},
                                  {"name": "c2", "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1}}}, )");
    writeText(dir / "used.gltf", text);
    Loaded r = tryLoad(dir / "used.gltf");
    ASSERT_EQ(r.error, "");
    EXPECT_EQ(countContaining(r.warnings, "EXT_magic"), 1u);
    EXPECT_EQ(countContaining(r.warnings, "'KHR_materials_clearcoat' is not supported: the clearcoat layer is not rendered"), 1u);
    EXPECT_EQ(countContaining(r.warnings, "KHR_materials_ior"), 0u);
    for (const std::string& w : r.warnings) {
        EXPECT_EQ(w.find('\n'), std::string::npos) << w;
        EXPECT_NE(w.find((dir / "used.gltf").string()), std::string::npos) << "a warning names its file: " << w;
    }
    EXPECT_EQ(r.warnings.size(), 2u);
}

TEST(GltfExtensions, RequiredButUnsupportedIsAnErrorAtTheCommandLine) {
    fs::path dir = test::tempDir("ext-required");
    writeTriangleBin(dir, "t.bin");
    std::string text = triangleGltf("t.bin", R"("extensionsUsed": ["KHR_draco_mesh_compression"], "extensionsRequired": ["KHR_draco_mesh_compression"], )",
                                    "", R"([{"mesh": 0}, {"camera": 0, "translation": [0, 0, 3]}])");
    text.replace(text.find(R"("scenes": [{"nodes": [0]}])"), std::strlen(R"("scenes": [{"nodes": [0]}])"),
                 R"("scenes": [{"nodes": [0, 1]}], "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}])");
    writeText(dir / "draco.gltf", text);
    Loaded r = tryLoad(dir / "draco.gltf");
    EXPECT_NE(r.error.find("extensionsRequired"), std::string::npos) << r.error;
    EXPECT_NE(r.error.find("'KHR_draco_mesh_compression'"), std::string::npos) << r.error;
    EXPECT_NE(r.error.find("without mesh compression"), std::string::npos) << r.error;

    std::string cmd = std::string(TESSERA_BINARY) + " render " + (dir / "draco.gltf").string() + " --quiet -o " +
                      (dir / "x.exr").string() + " 2> " + (dir / "err.txt").string();
    int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 2);
    std::ifstream in(dir / "err.txt");
    std::string line, all;
    int lines = 0;
    while (std::getline(in, line)) {
        ++lines;
        all += line;
    }
    EXPECT_EQ(lines, 1) << all;
    EXPECT_NE(all.find("KHR_draco_mesh_compression"), std::string::npos) << all;
}

TEST(GltfExtensions, DracoIsUsedOnlyThroughItsUncompressedFallback) {
    fs::path dir = test::tempDir("ext-draco");
    writeTriangleBin(dir, "t.bin");
    const std::string draco = R"(, "extensions": {"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}})";
    // With the uncompressed accessors present, the file renders from them, with one warning.
    writeText(dir / "fallback.gltf", triangleGltf("t.bin", R"("extensionsUsed": ["KHR_draco_mesh_compression"], )", draco));
    Loaded ok = tryLoad(dir / "fallback.gltf");
    EXPECT_EQ(ok.error, "");
    EXPECT_EQ(countContaining(ok.warnings, "KHR_draco_mesh_compression"), 1u);
    // Without them (POSITION has no bufferView: only the Draco stream holds the vertices) it is refused.
    std::string text = triangleGltf("t.bin", R"("extensionsUsed": ["KHR_draco_mesh_compression"], )", draco);
    text.replace(text.find(R"({"bufferView": 0, "componentType": 5126)"), std::strlen(R"({"bufferView": 0, "componentType": 5126)"),
                 R"({"componentType": 5126)");
    writeText(dir / "only.gltf", text);
    Loaded bad = tryLoad(dir / "only.gltf");
    EXPECT_NE(bad.error.find("meshes[0].primitives[0]"), std::string::npos) << bad.error;
    EXPECT_NE(bad.error.find("Draco"), std::string::npos) << bad.error;
}

TEST(GltfExtensions, MeshQuantizationReadsIntegerPositionsAndNormals) {
    fs::path dir = test::tempDir("ext-quantization");
    // Positions as normalized SHORT (32767 -> 1, -32768 -> -1), normals as normalized BYTE, each
    // VEC3 padded to 4-byte strides as the extension requires; and positions as plain UNSIGNED_SHORT.
    std::vector<unsigned char> bin(72, 0);
    const int16_t pos[3][4] = {{0, 0, 0, 0}, {32767, 0, 0, 0}, {0, -32768, 16384, 0}};
    const int8_t nrm[3][4] = {{0, 0, 127, 0}, {0, 0, 127, 0}, {-128, 0, 0, 0}};
    const uint16_t upos[3][2] = {{0, 0}, {3, 0}, {0, 5}};  // x, y pairs; z added below
    std::memcpy(bin.data(), pos, 24);
    std::memcpy(bin.data() + 24, nrm, 12);
    const uint32_t ix[3] = {0, 1, 2};
    std::memcpy(bin.data() + 36, ix, 12);
    for (int i = 0; i < 3; ++i) {
        const uint16_t v[3] = {upos[i][0], upos[i][1], 7};
        std::memcpy(bin.data() + 48 + 8 * i, v, 6);
    }
    writeFile(dir / "q.bin", bin.data(), bin.size());
    std::string text = R"({"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_mesh_quantization"], "extensionsRequired": ["KHR_mesh_quantization"],
      "scene": 0, "scenes": [{"nodes": [0, 1]}],
      "nodes": [{"mesh": 0, "scale": [2, 2, 2]}, {"mesh": 1}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]},
                 {"primitives": [{"attributes": {"POSITION": 3}, "indices": 2}]}],
      "buffers": [{"byteLength": 72, "uri": "q.bin"}],
      "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 24, "byteStride": 8},
                      {"buffer": 0, "byteOffset": 24, "byteLength": 12, "byteStride": 4},
                      {"buffer": 0, "byteOffset": 36, "byteLength": 12},
                      {"buffer": 0, "byteOffset": 48, "byteLength": 24, "byteStride": 8}],
      "accessors": [{"bufferView": 0, "componentType": 5122, "normalized": true, "count": 3, "type": "VEC3", "min": [0,-1,0], "max": [1,0,0.5]},
                    {"bufferView": 1, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3"},
                    {"bufferView": 2, "componentType": 5125, "count": 3, "type": "SCALAR"},
                    {"bufferView": 3, "componentType": 5123, "count": 3, "type": "VEC3", "min": [0,0,7], "max": [3,5,7]}]})";
    writeText(dir / "q.gltf", text);
    std::vector<std::string> warnings;
    Scene s = loadGltfScene((dir / "q.gltf").string(), warnings);
    EXPECT_TRUE(warnings.empty());
    ASSERT_EQ(s.geometry.meshes.size(), 2u);
    const TriangleMesh& m = s.geometry.meshes[0];
    ASSERT_EQ(m.positions.size(), 3u);
    EXPECT_EQ(m.positions[1], Vec3f(2.f, 0.f, 0.f));                      // 32767 / 32767 × scale 2
    EXPECT_EQ(m.positions[2], Vec3f(0.f, -2.f, 2.f * 16384.f / 32767.f)); // −32768 clamps to −1
    ASSERT_EQ(m.normals.size(), 3u);
    EXPECT_EQ(m.normals[0], Vec3f(0.f, 0.f, 1.f));
    EXPECT_EQ(m.normals[2], Vec3f(-1.f, 0.f, 0.f));  // −128 / 127 clamps to −1
    const TriangleMesh& u = s.geometry.meshes[1];
    ASSERT_EQ(u.positions.size(), 3u);
    EXPECT_EQ(u.positions[1], Vec3f(3.f, 0.f, 7.f));
    EXPECT_EQ(u.positions[2], Vec3f(0.f, 5.f, 7.f));
}

TEST(GltfExtensions, IgnoredCoreFeaturesAreNamedOnce) {
    fs::path dir = test::tempDir("ignored-features");
    writeTriangleBin(dir, "t.bin");
    std::string text = triangleGltf("t.bin", "", "");
    // COLOR_0 on the primitive (it reuses the position accessor: any VEC3 float is a valid colour).
    text.replace(text.find(R"("attributes": {"POSITION": 0})"), std::strlen(R"("attributes": {"POSITION": 0})"),
                 R"("attributes": {"POSITION": 0, "COLOR_0": 0})");
    writeText(dir / "colors.gltf", text);
    Loaded r = tryLoad(dir / "colors.gltf");
    ASSERT_EQ(r.error, "");
    EXPECT_EQ(countContaining(r.warnings, "COLOR_0"), 1u);
    EXPECT_EQ(r.warnings.size(), 1u);
}

// ===== TESSERA_asset_gltf ==========================================================================

namespace {

/// An asset folder holding "kit/part.gltf": the triangle under a parent node (translation (1, 0, 0))
/// whose child (scale 2) holds the mesh; its material is "red"; it has a camera, which is not used.
fs::path makeAssetRoot(const std::string& name) {
    fs::path root = test::tempDir(name) / "assets";
    writeTriangleBin(root / "kit", "part.bin");
    std::string text = triangleGltf("part.bin", "", "",
                                    R"([{"translation": [1, 0, 0], "children": [1]}, {"mesh": 0, "scale": [2, 2, 2]}, {"camera": 0}])");
    text.replace(text.find(R"("scenes": [{"nodes": [0]}])"), std::strlen(R"("scenes": [{"nodes": [0]}])"),
                 R"("scenes": [{"nodes": [0, 2]}], "cameras": [{"type": "perspective", "perspective": {"yfov": 0.3, "znear": 0.1}}])");
    writeText(root / "kit" / "part.gltf", text);
    return root;
}

/// A scene (next to the asset root) with one material of its own, a camera and `node` as node 0.
fs::path makeSceneUsing(const fs::path& root, const std::string& node) {
    fs::path path = root.parent_path() / "scene.gltf";
    writeText(path, R"({"asset": {"version": "2.0"}, "extensionsUsed": ["TESSERA_asset_gltf"], "extensionsRequired": ["TESSERA_asset_gltf"],
      "scene": 0, "scenes": [{"nodes": [0, 1]}],
      "nodes": [)" + node + R"(, {"camera": 0, "translation": [0, 0, 9]}],
      "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
      "materials": [{"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0}}]})");
    return path;
}

}  // namespace

TEST(GltfAsset, ImportsMeshesMaterialsAndHierarchyUnderTheNode) {
    fs::path root = makeAssetRoot("asset-import");
    fs::path scenePath = makeSceneUsing(root, R"({"translation": [0, 5, 0], "scale": [3, 3, 3],
        "extensions": {"TESSERA_asset_gltf": {"asset": "kit/part.gltf"}}})");
    std::vector<std::string> warnings;
    SceneLoadOptions options;
    options.assetRoots = {root.string()};
    Scene s = loadGltfScene(scenePath.string(), warnings, options);
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    ASSERT_EQ(s.geometry.meshes.size(), 1u);
    const TriangleMesh& m = s.geometry.meshes[0];
    // World = T(0, 5, 0) S(3) · T(1, 0, 0) S(2): p -> (3 + 6 x, 5 + 6 y, 6 z).
    ASSERT_EQ(m.positions.size(), 3u);
    EXPECT_EQ(m.positions[0], Vec3f(3.f, 5.f, 0.f));
    EXPECT_EQ(m.positions[1], Vec3f(9.f, 5.f, 0.f));
    EXPECT_EQ(m.positions[2], Vec3f(3.f, 11.f, 0.f));
    // The asset's material follows the scene's own (and each file's default material).
    ASSERT_LT(m.materialId, s.materials.size());
    EXPECT_EQ(s.materials[m.materialId].name, "red");
    EXPECT_EQ(s.materials[m.materialId].bsdf.baseColor, Rgb(1.f, 0.f, 0.f));
    EXPECT_EQ(s.materials[0].name, "floor");
    EXPECT_EQ(m.materialId, 2u);  // floor, the scene's default, then the asset's red
    ASSERT_TRUE(s.camera.has_value());
    EXPECT_FLOAT_EQ(s.camera->yfov, 0.8f) << "the asset's camera must not replace the scene's";
}

TEST(GltfAsset, MirroringNodeKeepsFrontFacesFacingTheMirroredWay) {
    fs::path root = makeAssetRoot("asset-mirror");
    fs::path scenePath = makeSceneUsing(root, R"({"scale": [1, 1, -1], "extensions": {"TESSERA_asset_gltf": {"asset": "kit/part.gltf"}}})");
    std::vector<std::string> warnings;
    SceneLoadOptions options;
    options.assetRoots = {root.string()};
    Scene s = loadGltfScene(scenePath.string(), warnings, options);
    ASSERT_EQ(s.geometry.meshes.size(), 1u);
    const TriangleMesh& m = s.geometry.meshes[0];
    const glm::uvec3 t = m.triangles[0];
    // The triangle lies in z = 0 facing +z; z -> −z mirrors its front face to −z (glTF 2.0 §3.7.4).
    Vec3f n = glm::cross(m.positions[t.y] - m.positions[t.x], m.positions[t.z] - m.positions[t.x]);
    EXPECT_LT(n.z, 0.f);
}

TEST(GltfAsset, ErrorsNameTheNodeTheAssetAndTheProblem) {
    fs::path root = makeAssetRoot("asset-errors");
    const std::string el = "nodes[0].extensions.TESSERA_asset_gltf";
    auto node = [](const std::string& asset) {
        return R"({"extensions": {"TESSERA_asset_gltf": {"asset": ")" + asset + R"("}}})";
    };
    struct Case {
        std::string asset, expect;
    };
    // A defective asset: an index out of range inside it.
    std::string broken = triangleGltf("part.bin");
    broken.replace(broken.find(R"("count": 3, "type": "SCALAR")"), std::strlen(R"("count": 3, "type": "SCALAR")"),
                   R"("count": 3, "type": "SCALAR", "byteOffset": 4)");
    writeText(root / "kit" / "broken.gltf", broken);
    // An asset that names itself.
    writeText(root / "kit" / "loop.gltf", R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"extensions": {"TESSERA_asset_gltf": {"asset": "kit/loop.gltf"}}}]})");
    writeText(root / "kit" / "mesh.ply", "ply\n");
    const std::vector<Case> cases = {
        {"kit/broken.gltf", "kit/broken.gltf"},  // the asset's own message follows, naming its file
        {"kit/missing.glb", "fetch_assets"},
        {"../escape.glb", "without '..'"},
        {"kit/mesh.ply", "only .glb and .gltf"},
        {"kit/loop.gltf", "nested deeper than"},
    };
    for (const Case& c : cases) {
        fs::path scenePath = makeSceneUsing(root, node(c.asset));
        Loaded r = tryLoad(scenePath, {root.string()});
        EXPECT_NE(r.error.find(scenePath.string()), std::string::npos) << c.asset << ": " << r.error;
        EXPECT_NE(r.error.find(el), std::string::npos) << c.asset << ": " << r.error;
        EXPECT_NE(r.error.find(c.expect), std::string::npos) << c.asset << ": " << r.error;
        EXPECT_EQ(r.error.find('\n'), std::string::npos) << r.error;
    }
    Loaded broken2 = tryLoad(makeSceneUsing(root, node("kit/broken.gltf")), {root.string()});
    EXPECT_NE(broken2.error.find("accessors[1]"), std::string::npos) << broken2.error;
}

// Every reference counts towards the limit on bytes read (--max-memory): a small scene naming an
// asset many times is refused at the reference that crosses it.
TEST(GltfAsset, RepeatedReferencesCountTowardsTheByteLimit) {
    fs::path root = makeAssetRoot("asset-budget");
    const std::string node = R"({"extensions": {"TESSERA_asset_gltf": {"asset": "kit/part.gltf"}}})";
    fs::path scenePath = root.parent_path() / "scene.gltf";
    writeText(scenePath, R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
      "nodes": [)" + node + "," + node + "," + node + "]}");
    const uint64_t assetSize = fs::file_size(root / "kit" / "part.gltf");
    SceneLoadOptions options;
    options.assetRoots = {root.string()};
    options.maxFileBytes = 2 * assetSize + assetSize / 2;  // two references fit, the third does not
    ASSERT_LT(fs::file_size(scenePath), options.maxFileBytes);
    std::vector<std::string> warnings;
    try {
        loadGltfScene(scenePath.string(), warnings, options);
        FAIL() << "the third reference must cross the limit";
    } catch (const SceneError& e) {
        std::string msg = e.what();
        EXPECT_NE(msg.find("nodes[2].extensions.TESSERA_asset_gltf"), std::string::npos) << msg;
        EXPECT_NE(msg.find("over the limit of " + std::to_string(options.maxFileBytes)), std::string::npos) << msg;
    }
    options.maxFileBytes = 3 * assetSize;
    EXPECT_EQ(loadGltfScene(scenePath.string(), warnings, options).geometry.meshes.size(), 3u);
}

// ===== The WebXR input-profile assets (fetched by tools/fetch_assets.sh) ===========================

namespace {

const char* const kWebxrLicense = "webxr-input-profiles/LICENSE.md";

/// Every GLB of the fetched package, as asset names "webxr-input-profiles/PROFILE/SIDE.glb", sorted.
std::vector<std::string> webxrAssets(const fs::path& packageFolder) {
    std::vector<std::string> names;
    for (const auto& profile : fs::directory_iterator(packageFolder))
        if (profile.is_directory())
            for (const auto& f : fs::directory_iterator(profile.path()))
                if (f.path().extension() == ".glb")
                    names.push_back("webxr-input-profiles/" + profile.path().filename().string() + "/" + f.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

}  // namespace

// The load survey, in four shards (models i with i % 4 == shard: each loads, decodes and renders a
// quarter of the 184 images in a few seconds): each of the 82 controller models loads with no
// error, has triangles and a controller's size (1 cm to 50 cm across: units and node transforms read
// right), and renders (two 16x12 ptnee images at 2 spp from cameras framing it) without a non-finite
// sample; the emissive models give a non-black image. The warnings are printed, one block per file.
class WebxrSurvey : public testing::TestWithParam<int> {};

TEST_P(WebxrSurvey, EveryModelLoadsAndRendersAndItsWarningsAreListed) {
    constexpr int kShards = 4;
    std::optional<std::string> license = test::findTestAsset(kWebxrLicense);
    if (!license) GTEST_SKIP() << test::missingAssetMessage(kWebxrLicense);
    std::vector<std::string> names = webxrAssets(fs::path(*license).parent_path());
    ASSERT_EQ(names.size(), 82u) << "the package has 82 GLBs: is the cache complete? (tools/fetch_assets.sh)";
    size_t models = 0, warned = 0, triangles = 0, emissive = 0;
    for (size_t i = size_t(GetParam()); i < names.size(); i += kShards) {
        const std::string& name = names[i];
        ++models;
        std::optional<std::string> path = test::findTestAsset(name);
        ASSERT_TRUE(path.has_value()) << name;
        std::vector<std::string> warnings;
        try {
            Scene s = loadGltfScene(*path, warnings);
            size_t tris = 0;
            Bounds3f b = s.geometry.bounds();
            for (const TriangleMesh& m : s.geometry.meshes) tris += m.triangles.size();
            triangles += tris;
            EXPECT_GT(tris, 100u) << name;  // the smallest, google-daydream, has 292
            float extent = glm::length(b.upper - b.lower);
            EXPECT_TRUE(extent > 0.01f && extent < 0.5f) << name << ": extent " << extent << " m";
            // Seen from behind-above and from front-above (grip space: −z points forward), where
            // the LEDs of the emissive models face.
            Vec3f centre = 0.5f * (b.lower + b.upper);
            double sum = 0;
            for (Vec3f dir : {Vec3f(0.6f, 0.5f, 1.f), Vec3f(-0.6f, 0.5f, -1.f)}) {
                Vec3f eye = centre + extent * glm::normalize(dir);
                s.camera = CameraDesc{};
                s.camera->cameraToWorld = glm::inverse(glm::lookAt(eye, centre, Vec3f(0.f, 1.f, 0.f)));
                s.camera->yfov = 0.9f;
                test::TestRender r = test::renderScene(s, "ptnee", 16, 12, RenderOptions{.spp = 2, .threads = 1, .seed = 3});
                EXPECT_EQ(r.stats.nonFiniteDropped, 0u) << name;
                for (float v : r.film.rgba()) {
                    ASSERT_TRUE(std::isfinite(v)) << name;
                    sum += v;
                }
            }
            if (s.lights().size() > 0) {
                ++emissive;
                EXPECT_GT(sum, 2 * 16.0 * 12.0) << name << ": emissive, yet black (alpha alone sums to 384)";
            }
        } catch (const std::exception& e) {
            ADD_FAILURE() << name << ": " << e.what();
        }
        if (!warnings.empty()) ++warned;
        for (const std::string& w : warnings) {
            size_t afterFile = w.find(*path) == 0 ? path->size() + 2 : 0;  // "FILE: " is the name already printed
            std::cout << "  " << name << ": " << w.substr(std::min(afterFile, w.size())) << "\n";
        }
    }
    std::cout << "shard " << GetParam() << ": " << models << " models, " << triangles << " triangles, " << emissive
              << " emissive, " << warned << " with warnings\n";
}

INSTANTIATE_TEST_SUITE_P(Shards, WebxrSurvey, testing::Range(0, 4));

// A scene importing a model by TESSERA_asset_gltf holds exactly the model's triangles, moved by the node.
TEST(WebxrAssets, SceneImportEqualsTheModelUnderTheNodeTransform) {
    const std::string name = "webxr-input-profiles/hp-mixed-reality/left.glb";
    std::optional<std::string> path = test::findTestAsset(name);
    if (!path) GTEST_SKIP() << test::missingAssetMessage(name);
    std::vector<std::string> warnings;
    Scene direct = loadGltfScene(*path, warnings);
    fs::path dir = test::tempDir("webxr-import");
    writeText(dir / "s.gltf", R"({"asset": {"version": "2.0"}, "extensionsUsed": ["TESSERA_asset_gltf"], "extensionsRequired": ["TESSERA_asset_gltf"],
      "scene": 0, "scenes": [{"nodes": [0]}],
      "nodes": [{"translation": [1, 2, 3], "rotation": [0, 0.7071067811865476, 0, 0.7071067811865476], "scale": [10, 10, 10],
                 "extensions": {"TESSERA_asset_gltf": {"asset": ")" + name + R"("}}}]})");
    SceneLoadOptions options;
    options.assetRoots = test::testAssetRoots();
    Scene imported = loadGltfScene((dir / "s.gltf").string(), warnings, options);
    ASSERT_EQ(imported.geometry.meshes.size(), direct.geometry.meshes.size());
    ASSERT_EQ(imported.materials.size(), direct.materials.size() + 1);  // + the scene's default material
    EXPECT_EQ(imported.images.size(), direct.images.size());
    EXPECT_EQ(imported.lights().size(), direct.lights().size());
    const Mat4d node = glm::translate(Mat4d(1.0), Vec3d(1, 2, 3)) * glm::mat4_cast(glm::dquat(0.7071067811865476, 0, 0.7071067811865476, 0)) *
                       glm::scale(Mat4d(1.0), Vec3d(10.0));
    for (size_t i = 0; i < direct.geometry.meshes.size(); ++i) {
        const TriangleMesh &a = direct.geometry.meshes[i], &b = imported.geometry.meshes[i];
        ASSERT_EQ(a.triangles.size(), b.triangles.size()) << a.name;
        EXPECT_EQ(imported.materials[b.materialId].name, direct.materials[a.materialId].name);
        for (size_t v = 0; v < a.positions.size(); v += 97) {
            Vec3f expect = Vec3f(node * glm::dvec4(Vec3d(a.positions[v]), 1.0));
            EXPECT_LT(glm::length(b.positions[v] - expect), 1e-5f) << a.name << " vertex " << v;
        }
    }
}

// The 18 Poly Haven HDRIs that tools/fetch_assets.sh decodes from @pmndrs/assets' base64 modules
// are whole EXRs: 512x256, finite, high dynamic range (max > 1), not black. Their DWAB compression
// is lossy: ringing around the sun leaves negative texels in every one of them (17 to 6,524 of the
// 131,072; esplanade down to −3894 next to +29,860), so an environment light must clamp them to 0.
TEST(FetchedHdris, AllEighteenDecodeAs512By256RadianceImages) {
    const char* const names[] = {"apartment", "bridge", "city",  "dawn",  "esplanade", "forest",
                                 "hall",      "lab",    "lobby", "night", "park",      "sky",
                                 "studio",    "sunrise", "sunset", "venice", "warehouse", "workshop"};
    for (const char* n : names) {
        const std::string name = std::string("pmndrs-hdri/") + n + ".exr";
        std::optional<std::string> path = test::findTestAsset(name);
        if (!path) GTEST_SKIP() << test::missingAssetMessage(name);
        Image image = readImageFile(*path, ColorEncoding::Linear);
        ASSERT_EQ(image.width(), 512) << name;
        ASSERT_EQ(image.height(), 256) << name;
        double sum = 0, maxValue = 0;
        size_t negative = 0;
        for (const Vec4f& t : image.levels[0].texels) {
            for (int c = 0; c < 3; ++c) {
                ASSERT_TRUE(std::isfinite(t[c])) << name;
                sum += std::max(t[c], 0.f);
                maxValue = std::max(maxValue, double(t[c]));
            }
            negative += (t.x < 0.f || t.y < 0.f || t.z < 0.f) ? 1 : 0;
        }
        EXPECT_GT(sum / (3.0 * 512 * 256), 0.03) << name << " is nearly black";
        EXPECT_GT(maxValue, 1.0) << name << " is not high dynamic range";
        EXPECT_LT(negative, 512u * 256u / 16) << name << ": " << negative << " negative texels";
    }
}
