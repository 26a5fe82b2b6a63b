// Textures and normal maps seen through the renderer. The textured quads are lit by a closed
// emitting sphere (Le = 1) and rendered by pt with one bounce: a Lambertian point of albedo ρ then
// returns exactly ρ for every sample (cosine-sampled weight ρ times Le = 1), so each pixel is the
// mean of the filtered texture over the pixel, known analytically.
#include <gtest/gtest.h>

#include <cmath>

#include "gltf_test_files.h"
#include "integrators/integrator.h"
#include "render/film.h"
#include "scene/gltf_loader.h"
#include "scene/tangents.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

constexpr float kYfov = 0.8f;
constexpr int kRes = 64;

/// A square quad at z = −`dist` facing the camera at the origin (looking down −z), exactly filling
/// the square image; uv = (0, 0) at the top-left corner, v downwards (glTF's image orientation).
TriangleMesh frontQuad(float dist, uint32_t material) {
    float h = dist * std::tan(0.5f * kYfov);
    TriangleMesh m;
    m.name = "quad";
    m.positions = {{-h, h, -dist}, {h, h, -dist}, {h, -h, -dist}, {-h, -h, -dist}};
    m.normals = std::vector<Vec3f>(4, Vec3f(0, 0, 1));
    m.texcoords[0] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    m.triangles = {{0, 3, 2}, {0, 2, 1}};  // counter-clockwise seen from +z
    m.materialId = material;
    return m;
}

/// The textured quad (material 0: Lambertian, baseColor × `texture`) inside an emitting sphere.
Scene furnaceQuad(const Image& image, FilterMode filter, WrapMode wrap) {
    Scene scene;
    Material quad;
    quad.bsdf.baseColor = Rgb(1.f);
    quad.bsdf.specular = 0.f;  // KHR_materials_specular 0: a pure Lambertian
    quad.textures.baseColor.image = &image;
    quad.textures.baseColor.filter = filter;
    quad.textures.baseColor.wrapS = quad.textures.baseColor.wrapT = wrap;
    Material light;
    light.bsdf.baseColor = Rgb(0.f);
    light.emission = Rgb(1.f);
    light.doubleSided = true;
    scene.materials = {quad, light};
    scene.geometry.meshes.push_back(frontQuad(1.f, 0));
    scene.geometry.spheres.push_back(Sphere{"sky", Vec3f(0.f), 10.f, 1});
    scene.finalize();
    scene.camera = CameraDesc{};
    scene.camera->yfov = kYfov;
    return scene;
}

Film renderPt(const Scene& scene, int spp, int threads = 2) {
    RenderOptions options;
    options.spp = spp;
    options.seed = 7;
    options.threads = threads;
    return test::renderScene(scene, "pt", kRes, kRes, options, "bvh", 1).film;
}

/// Checks every pixel against the texels its samples can reach: a pixel inside one texel (nearest)
/// or inside the linear region of the interpolation equals it to rounding; any other pixel lies
/// between the smallest and largest value the texture takes over the pixel. Returns the number of
/// pixels that were checked exactly.
template <class Expected>
int checkPixels(const Film& film, Expected range) {
    int exact = 0;
    for (int y = 0; y < kRes; ++y)
        for (int x = 0; x < kRes; ++x) {
            Rgb p = film.pixel(x, y);
            auto [lo, hi] = range(x, y);
            for (int c = 0; c < 3; ++c) {
                EXPECT_GE(p[c], lo[c] - 2e-5f) << x << "," << y << " channel " << c;
                EXPECT_LE(p[c], hi[c] + 2e-5f) << x << "," << y << " channel " << c;
            }
            exact += lo == hi;
        }
    return exact;
}

}  // namespace

// Nearest filtering: an 8×8 checkerboard over 64×64 pixels (8 pixels per texel).
TEST(TexturedQuad, NearestCheckerboardIsReproducedPixelForPixel) {
    auto texel = [](int x, int y) {
        bool odd = (x + y) % 2;
        return Vec4f(odd ? 0.9f : 0.1f, 0.05f + 0.1f * float(x), 0.05f + 0.1f * float(y), 1.f);
    };
    Image image = test::imageFromTexels(8, 8, texel);
    Scene scene = furnaceQuad(image, FilterMode::Nearest, WrapMode::ClampToEdge);
    Film film = renderPt(scene, 8);
    int exact = checkPixels(film, [&](int x, int y) {
        // Texels the pixel's uv square [x, x + 1]/64 can reach, padded for rounding at texel edges.
        int x0 = std::max(0, int(std::floor((float(x) - 0.01f) / 8.f))), x1 = std::min(7, int(std::floor((float(x) + 1.01f) / 8.f)));
        int y0 = std::max(0, int(std::floor((float(y) - 0.01f) / 8.f))), y1 = std::min(7, int(std::floor((float(y) + 1.01f) / 8.f)));
        Vec3f lo(1e9f), hi(-1e9f);
        for (int ty = y0; ty <= y1; ++ty)
            for (int tx = x0; tx <= x1; ++tx) lo = glm::min(lo, Vec3f(texel(tx, ty))), hi = glm::max(hi, Vec3f(texel(tx, ty)));
        return std::pair{lo, hi};
    });
    EXPECT_EQ(exact, 50 * 50);  // the 6 × 6 pixels inside each texel, and the image's outer rows and columns
}

// Bilinear filtering of a 16×16 gradient: texel (i, j) = ((i + ½)/16, (j + ½)/16), so the filtered
// value is (u, v) itself between the outer texel centres (clamped outside them).
TEST(TexturedQuad, BilinearGradientIsReproducedWithinFilteringError) {
    auto texel = [](int x, int y) { return Vec4f((float(x) + 0.5f) / 16.f, (float(y) + 0.5f) / 16.f, 0.5f, 1.f); };
    Image image = test::imageFromTexels(16, 16, texel);
    Scene scene = furnaceQuad(image, FilterMode::Linear, WrapMode::ClampToEdge);
    Film film = renderPt(scene, 8);
    auto filtered = [](float u) { return std::clamp(u, 0.5f / 16.f, 15.5f / 16.f); };
    double sumError = 0.0;
    int n = 0;
    checkPixels(film, [&](int x, int y) {
        Vec3f lo(filtered(float(x) / kRes), filtered(float(y) / kRes), 0.5f);
        Vec3f hi(filtered(float(x + 1) / kRes), filtered(float(y + 1) / kRes), 0.5f);
        Rgb p = film.pixel(x, y);
        sumError += double(p.r) - 0.5 * (lo.x + hi.x) + double(p.g) - 0.5 * (lo.y + hi.y);
        n += 2;
        return std::pair{lo, hi};
    });
    // The pixel means scatter around the pixel-centre values with no bias (a half-texel shift
    // would be 1/32).
    EXPECT_LT(std::abs(sumError / n), 2e-4);
}

// The MIP level comes from the camera footprint at the hit, a function of the point only: the
// image is the same bits whatever the thread count.
TEST(TexturedQuad, FilteredImageDoesNotDependOnThreadCount) {
    Image image = test::imageFromTexels(256, 256, [](int x, int y) { return Vec4f(float((x ^ y) & 1), float(x) / 255.f, float(y) / 255.f, 1.f); });
    Scene scene = furnaceQuad(image, FilterMode::Linear, WrapMode::Repeat);
    Film one = renderPt(scene, 2, 1), four = renderPt(scene, 2, 4);
    EXPECT_EQ(one.rgba(), four.rgba());
    // 256 texels over 64 pixels: the footprint selects level 2, where the 1-texel checkerboard in
    // red has averaged to ½; level 0 would leave red at 0 or 1 in most samples.
    double meanDeviation = 0.0;
    for (int y = 8; y < 56; ++y)
        for (int x = 8; x < 56; ++x) meanDeviation += std::abs(one.pixel(x, y).r - 0.5);
    EXPECT_LT(meanDeviation / (48 * 48), 0.05);
}

// End to end through the loader: 8-bit sRGB PNG codes render as their linear values.
TEST(TexturedQuad, SrgbPngBaseColorRendersAsItsLinearValues) {
    auto dir = test::tempDir("srgb-end-to-end");
    std::vector<uint8_t> px;
    for (int i = 0; i < 16; ++i) px.insert(px.end(), {uint8_t(i * 17), uint8_t(255 - i * 13), uint8_t(40 + i * 9)});
    test::GltfBuilder b;
    float h = std::tan(0.5f * kYfov);
    nlohmann::json prim = {{"attributes",
                            {{"POSITION", b.positions({-h, h, -1, h, h, -1, h, -h, -1, -h, -h, -1})},
                             {"TEXCOORD_0", b.floats({0, 0, 1, 0, 1, 1, 0, 1}, 2, "VEC2")}}},
                           {"indices", b.indices({0, 3, 2, 0, 2, 1})},
                           {"material", 0}};
    b.doc["meshes"] = {{{"primitives", {prim}}}};
    b.doc["samplers"] = {{{"magFilter", 9728}}};
    b.doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", b.texture(b.image(test::pngBytes(4, 4, 3, px), true), 0)}}}, {"metallicFactor", 0}}},
                           {"extensions", {{"KHR_materials_specular", {{"specularFactor", 0}}}}}},
                          {{"pbrMetallicRoughness", {{"baseColorFactor", {0, 0, 0, 1}}}}, {"emissiveFactor", {1, 1, 1}}, {"doubleSided", true}}};
    b.doc["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", kYfov}, {"znear", 0.01}}}}};
    b.doc["nodes"] = {{{"mesh", 0}}, {{"camera", 0}}, {{"extensions", {{"TESSERA_sphere", {{"radius", 10}, {"material", 1}}}}}}};
    b.doc["scenes"] = {{{"nodes", {0, 1, 2}}}};
    b.doc["scene"] = 0;
    b.doc["extensionsUsed"] = {"KHR_materials_specular", "TESSERA_sphere"};
    b.write((dir / "srgb.glb").string());
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene((dir / "srgb.glb").string(), warnings);
    Film film = renderPt(scene, 4);
    for (int ty = 0; ty < 4; ++ty)
        for (int tx = 0; tx < 4; ++tx)
            for (int y = ty * 16 + 1; y < ty * 16 + 15; ++y)
                for (int x = tx * 16 + 1; x < tx * 16 + 15; ++x)
                    for (int c = 0; c < 3; ++c) {
                        double v = px[size_t(3 * (ty * 4 + tx) + c)] / 255.0;
                        double linear = v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
                        ASSERT_NEAR(film.pixel(x, y)[c], linear, 2e-5) << x << "," << y << " channel " << c;
                    }
}

namespace {

/// A small Lambertian quad (albedo 0.5) at z = −1 lit by a distant point light, rendered with
/// ptnee (direct light only). `tilt` rotates the geometry about the axis `axis` (x or y) through
/// the quad's centre; `mapTilt` instead gives the flat quad a constant normal map of that tilt.
Film renderLitQuad(Vec3f lightDir, float tilt, float mapTilt, int axis, Image& normalMap) {
    Scene scene;
    Material m;
    m.bsdf.baseColor = Rgb(0.5f);
    m.bsdf.specular = 0.f;
    Vec3f tiltedNormal = axis == 0 ? Vec3f(std::sin(mapTilt), 0.f, std::cos(mapTilt)) : Vec3f(0.f, std::sin(mapTilt), std::cos(mapTilt));
    normalMap = test::imageFromTexels(2, 2, [&](int, int) { return Vec4f(0.5f * (tiltedNormal + 1.f), 1.f); });
    if (mapTilt != 0.f) m.textures.normal.image = &normalMap;
    scene.materials = {m};
    TriangleMesh q = frontQuad(1.f, 0);
    Vec3f centre(0.f, 0.f, -1.f);
    for (Vec3f& p : q.positions) {
        p = 0.25f * (p - centre);  // a quarter of the view
        Vec3f r = p;
        if (axis == 0) r = Vec3f(p.x * std::cos(tilt) + p.z * std::sin(tilt), p.y, -p.x * std::sin(tilt) + p.z * std::cos(tilt));
        else r = Vec3f(p.x, p.y * std::cos(tilt) + p.z * std::sin(tilt), -p.y * std::sin(tilt) + p.z * std::cos(tilt));
        p = centre + r;
    }
    Vec3f n = glm::normalize(glm::cross(q.positions[3] - q.positions[0], q.positions[2] - q.positions[0]));
    q.normals = std::vector<Vec3f>(4, n);
    // The tangent frame an exporter writes for this uv layout (v down the image = −y): T = ∂p/∂u =
    // +x, w = +1, so B = N × T = +y, up the image, where a normal map's +Y (green) points.
    q.tangents = std::vector<Vec4f>(4, Vec4f(1.f, 0.f, 0.f, 1.f));
    scene.geometry.meshes.push_back(q);
    scene.pointLights.push_back(PointLightDesc{centre + 100.f * lightDir, Rgb(1e4f)});
    scene.finalize();
    scene.camera = CameraDesc{};
    scene.camera->yfov = kYfov;
    RenderOptions options;
    options.spp = 4;
    options.seed = 3;
    return test::renderScene(scene, "ptnee", kRes, kRes, options, "bvh").film;
}

double centreMean(const Film& film) {
    double sum = 0.0;
    for (int y = 26; y < 38; ++y)
        for (int x = 26; x < 38; ++x) sum += film.pixel(x, y).r;
    return sum / 144.0;
}

}  // namespace

// A flat quad with a normal map of a known tilt shades like the quad tilted in geometry, and both
// match ρ/π · I · cos θ / d²; without the map it does not. Tilts about y (red channel, T) and
// about x (green channel, B = w · N × T).
TEST(NormalMap, ConstantTiltMatchesTheSameTiltInGeometry) {
    const float alpha = 0.5f;
    for (int axis : {0, 1}) {
        Vec3f lightDir = axis == 0 ? glm::normalize(Vec3f(0.8f, 0.f, 1.f)) : glm::normalize(Vec3f(0.f, 0.8f, 1.f));
        Image mapA, mapB, mapC;
        double mapped = centreMean(renderLitQuad(lightDir, 0.f, alpha, axis, mapA));
        double geometric = centreMean(renderLitQuad(lightDir, alpha, 0.f, axis, mapB));
        double plain = centreMean(renderLitQuad(lightDir, 0.f, 0.f, axis, mapC));
        Vec3f tilted = axis == 0 ? Vec3f(std::sin(alpha), 0.f, std::cos(alpha)) : Vec3f(0.f, std::sin(alpha), std::cos(alpha));
        double expected = 0.5 / kPi * 1e4 * glm::dot(tilted, lightDir) / (100.0 * 100.0);
        EXPECT_NEAR(mapped, expected, 2e-3 * expected) << "axis " << axis;
        EXPECT_NEAR(geometric, expected, 2e-3 * expected) << "axis " << axis;
        EXPECT_NEAR(mapped, geometric, 2e-3 * expected) << "axis " << axis;
        EXPECT_GT(std::abs(plain - expected), 0.05 * expected) << "axis " << axis;
    }
}

// End to end: a glTF quad (uv v down the image, no TANGENT) with a one-texel normal-map PNG tilted
// towards +Y (green) or +X (red): the loader's MikkTSpace tangents must put green up the image
// (+y here) and red along +u (+x), so that the quad shades like the tilted normal n decoded from
// the texel's 8-bit codes, ρ/π · I · (n · l) / d².
TEST(NormalMap, GltfNormalTextureWithGeneratedTangentsFollowsTheImageAxes) {
    auto dir = test::tempDir("normal-map-gltf");
    const float alpha = 0.5f, h = 0.25f * std::tan(0.5f * kYfov);
    for (int axis : {0, 1}) {
        Vec3f tilt = axis == 0 ? Vec3f(std::sin(alpha), 0.f, std::cos(alpha)) : Vec3f(0.f, std::sin(alpha), std::cos(alpha));
        std::vector<uint8_t> texel;
        for (int c = 0; c < 3; ++c) texel.push_back(uint8_t(std::lround(255.0 * (tilt[c] + 1.0) / 2.0)));
        Vec3f decoded = glm::normalize(Vec3f(texel[0], texel[1], texel[2]) * (2.f / 255.f) - 1.f);
        Vec3f lightDir = axis == 0 ? glm::normalize(Vec3f(0.8f, 0.f, 1.f)) : glm::normalize(Vec3f(0.f, 0.8f, 1.f));
        test::GltfBuilder b;
        nlohmann::json prim = {{"attributes",
                                {{"POSITION", b.positions({-h, h, -1, h, h, -1, h, -h, -1, -h, -h, -1})},
                                 {"NORMAL", b.floats({0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}, 3, "VEC3")},
                                 {"TEXCOORD_0", b.floats({0, 0, 1, 0, 1, 1, 0, 1}, 2, "VEC2")}}},
                               {"indices", b.indices({0, 3, 2, 0, 2, 1})},
                               {"material", 0}};
        b.doc["meshes"] = {{{"primitives", {prim}}}};
        b.doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.5, 0.5, 1}}, {"metallicFactor", 0}}},
                               {"normalTexture", {{"index", b.texture(b.image(test::pngBytes(1, 1, 3, texel), true))}}},
                               {"extensions", {{"KHR_materials_specular", {{"specularFactor", 0}}}}}}};
        Vec3f light = Vec3f(0.f, 0.f, -1.f) + 100.f * lightDir;
        b.doc["extensions"] = {{"KHR_lights_punctual", {{"lights", {{{"type", "point"}, {"intensity", 1e4}}}}}}};
        b.doc["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", kYfov}, {"znear", 0.01}}}}};
        b.doc["nodes"] = {{{"mesh", 0}},
                          {{"camera", 0}},
                          {{"translation", {light.x, light.y, light.z}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}}};
        b.doc["scenes"] = {{{"nodes", {0, 1, 2}}}};
        b.doc["scene"] = 0;
        b.doc["extensionsUsed"] = {"KHR_materials_specular", "KHR_lights_punctual"};
        std::string path = (dir / ("n" + std::to_string(axis) + ".glb")).string();
        b.write(path);
        std::vector<std::string> warnings;
        Scene scene = loadGltfScene(path, warnings);
        ASSERT_FALSE(scene.geometry.meshes[0].tangents.empty());
        RenderOptions options;
        options.spp = 4;
        options.seed = 5;
        double mean = centreMean(test::renderScene(scene, "ptnee", kRes, kRes, options, "bvh").film);
        double expected = 0.5 / kPi * glm::dot(decoded, lightDir);
        EXPECT_NEAR(mean, expected, 2e-3 * expected) << "axis " << axis;
    }
}

// Every integrator sees the same textures: in a closed sphere (seen from inside) whose surface has
// a checkerboard albedo, a random-tilt normal map (MikkTSpace tangents) and a textured emission
// (emission varying over every light triangle, each selected by its textured power), pt,
// lt and bdpt agree with ptnee bin by bin (4×4-pixel bins, 16 independent batches each: z from the
// batch variances, Šidák-corrected over bins and channels). The MIP level is a function of the hit
// point (Camera::pixelFootprint), so camera and light sub-paths read the same filtered values.
TEST(TexturedAgreement, EveryIntegratorAgreesInATexturedNormalMappedEmissiveTexturedFurnace) {
    Image albedo = test::imageFromTexels(8, 4, [](int x, int y) { return (x + y) % 2 ? Vec4f(0.85f, 0.5f, 0.3f, 1.f) : Vec4f(0.3f, 0.6f, 0.75f, 1.f); });
    uint32_t state = 2024u;
    auto uniform = [&] {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) / float(1u << 24);
    };
    Image bumps = test::imageFromTexels(16, 8, [&](int, int) {
        Vec3f n = glm::normalize(Vec3f(0.8f * (uniform() - 0.5f), 0.8f * (uniform() - 0.5f), 1.f));
        return Vec4f(0.5f * (n + 1.f), 1.f);
    });
    Scene scene;
    Material m;
    m.bsdf.baseColor = Rgb(1.f);
    m.bsdf.specular = 0.f;
    m.emission = Rgb(0.5f);
    m.doubleSided = true;
    Image glow = test::imageFromTexels(6, 3, [](int x, int y) {
        return (x + 2 * y) % 3 == 0 ? Vec4f(1.f, 0.6f, 0.3f, 1.f) : Vec4f(0.15f, 0.3f, 0.9f, 1.f);
    });
    m.textures.emissive.image = &glow;
    m.textures.baseColor.image = &albedo;
    m.textures.normal.image = &bumps;
    scene.materials.push_back(m);
    Vec3f centre(0.1f, -0.2f, 0.05f);
    TriangleMesh mesh = test::makeUvSphereMesh(centre, 1.f, 24, 48, 0);
    for (const Vec3f& p : mesh.positions) {
        mesh.normals.push_back(glm::normalize(p - centre));
        Vec3f d = glm::normalize(p - centre);
        mesh.texcoords[0].emplace_back(std::atan2(d.z, d.x) / (2.f * kPi) + 0.5f, std::acos(std::clamp(d.y, -1.f, 1.f)) / kPi);
    }
    // The seam column (phi = 2π) gets u = 1, not 0, so no triangle wraps through the whole texture.
    for (int r = 0; r <= 24; ++r) mesh.texcoords[0][size_t(r * 49 + 48)].x = mesh.texcoords[0][size_t(r * 49)].x + 1.f;
    generateMikkTangents(mesh, 0);
    scene.geometry.meshes.push_back(mesh);
    scene.finalize();
    scene.camera = CameraDesc{};
    scene.camera->yfov = 1.2f;

    const int res = 24, bin = 4, bins = res / bin, batches = 16;
    auto binMoments = [&](const char* name, int spp) {
        std::vector<double> sum(size_t(bins * bins * 3), 0.0), sumSq(sum.size(), 0.0);
        for (int b = 0; b < batches; ++b) {
            RenderOptions options;
            options.spp = spp;
            options.seed = 500 + uint64_t(b);
            options.threads = 2;
            Film film = test::renderScene(scene, name, res, res, options, "embree").film;
            for (int by = 0; by < bins; ++by)
                for (int bx = 0; bx < bins; ++bx)
                    for (int c = 0; c < 3; ++c) {
                        double v = 0.0;
                        for (int y = 0; y < bin; ++y)
                            for (int x = 0; x < bin; ++x) v += film.pixel(bx * bin + x, by * bin + y)[c];
                        v /= bin * bin;
                        sum[size_t((by * bins + bx) * 3 + c)] += v;
                        sumSq[size_t((by * bins + bx) * 3 + c)] += v * v;
                    }
        }
        return std::pair{sum, sumSq};
    };
    auto [refSum, refSumSq] = binMoments("ptnee", 16);
    const double n = double(bins * bins * 3);
    const double alphaPerTest = 1.0 - std::pow(1.0 - 0.01, 1.0 / n);  // Šidák at 0.01
    for (auto [name, spp] : {std::pair{"pt", 16}, std::pair{"lt", 32}, std::pair{"bdpt", 8}}) {
        auto [sum, sumSq] = binMoments(name, spp);
        double minP = 1.0, meanA = 0.0, meanB = 0.0;
        std::string worst;
        for (size_t i = 0; i < size_t(n); ++i) {
            double ma = sum[i] / batches, mb = refSum[i] / batches;
            double va = std::max(0.0, (sumSq[i] - batches * ma * ma) / (batches - 1));
            double vb = std::max(0.0, (refSumSq[i] - batches * mb * mb) / (batches - 1));
            // The variances come from the batches themselves, so (ma − mb)/se is Student-t
            // distributed, heavier-tailed than normal: map it to a normal deviate with the standard
            // approximation z = t (1 − 1/(4ν)) / √(1 + t²/(2ν)), ν = batches − 1 (conservative).
            double t = (ma - mb) / std::sqrt((va + vb) / batches), nu = batches - 1.0;
            double z = t * (1.0 - 1.0 / (4.0 * nu)) / std::sqrt(1.0 + t * t / (2.0 * nu));
            double p = std::erfc(std::abs(z) / std::sqrt(2.0));
            if (p < minP) minP = p, worst = std::to_string(ma) + " vs " + std::to_string(mb) + " (t " + std::to_string(t) + ")";
            meanA += ma / n;
            meanB += mb / n;
        }
        EXPECT_GT(minP, alphaPerTest) << name << " vs ptnee: worst bin " << worst;
        EXPECT_NEAR(meanA, meanB, 0.01 * meanB) << name << " vs ptnee";
    }
}
