// Spot and directional lights (KHR_lights_punctual) in every integrator: analytic answers on a
// diffuse plane, light selection by power, and per-pixel agreement of the integrators on a spot-lit
// box.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <fstream>

#include "integrators/integrator.h"
#include "render/renderer.h"
#include "scene/gltf_loader.h"
#include "texture/texture.h"
#include "test_agreement.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

/// A Lambertian square of side 2·half in the plane y = 0, facing +y, seen from straight above.
Scene diffusePlane(Rgb albedo, float half) {
    Scene scene = test::diffusePlaneScene(albedo, half);
    CameraDesc cam;
    cam.cameraToWorld = glm::inverse(glm::lookAt(Vec3f(0.f, 3.f, 0.f), Vec3f(0.f), Vec3f(0.f, 0.f, -1.f)));
    cam.yfov = 0.9f;
    scene.camera = cam;
    return scene;
}

/// Looking down at the floor from above the emitter's height, off to the side.
CameraDesc lookAtCameraDown() {
    CameraDesc cam;
    cam.cameraToWorld = glm::inverse(glm::lookAt(Vec3f(0.f, 2.5f, 2.5f), Vec3f(0.f), Vec3f(0.f, 1.f, 0.f)));
    cam.yfov = 0.9f;
    return cam;
}

Film render(const Scene& scene, const std::string& integrator, int w, int h, int spp, uint64_t seed, int maxDepth = -1) {
    std::unique_ptr<Accel> accel = createAccel("embree", scene.geometry);
    std::unique_ptr<Integrator> in = createIntegrator(integrator);
    test::TestRender r = test::renderScene(scene, *accel, *in, w, h, RenderOptions{.spp = spp, .seed = seed, .tileSize = 16}, maxDepth);
    EXPECT_EQ(r.stats.nonFiniteDropped, 0u) << integrator;
    return std::move(r.film);
}

}  // namespace

// A directional light of irradiance E at angle θ from the normal of a Lambertian plane of albedo a:
// every point reflects L = (a/π) E cos θ. No BSDF sample can hit a delta direction, so `pt` gives 0.
TEST(DirectionalLight, DiffusePlaneReflectsAlbedoTimesIrradianceCosineOverPi) {
    const Rgb albedo(0.6f, 0.4f, 0.2f), E(2.f, 3.f, 4.f);
    Scene scene = diffusePlane(albedo, 4.f);
    const float theta = 0.5f;
    scene.directionalLights.push_back({Vec3f(std::sin(theta), -std::cos(theta), 0.f), E});
    scene.finalize();
    const Rgb expected = albedo * E * (std::cos(theta) / kPi);
    for (const char* name : {"ptnee", "lt", "bdpt", "pt"}) {
        bool lt = std::string(name) == "lt";
        Film film = render(scene, name, 16, 16, lt ? 512 : 8, 3);
        if (std::string(name) == "pt") {
            double mean[3], se[3];
            test::pixelMean(film, mean, se);
            EXPECT_EQ(mean[0] + mean[1] + mean[2], 0.0) << "pt cannot find a delta light";
            continue;
        }
        test::expectImageMean(film, expected, lt ? 0.01 : 0.005, name);
    }
}

// A spot light of axis intensity I above a Lambertian plane: L(x) = (a/π) I · falloff(cos φ) ·
// cos θ / d², with φ the angle off the axis and θ at the plane. The image mean must equal that
// radiance averaged over the image, computed here by casting a dense grid of rays at the plane
// analytically (independently of the renderer).
TEST(SpotLight, DiffusePlaneMatchesTheAnalyticFalloffIntegral) {
    const Rgb albedo(0.7f), I(5.f, 4.f, 3.f);
    Scene scene = diffusePlane(albedo, 6.f);
    SpotLightDesc spot;
    spot.position = Vec3f(0.4f, 1.2f, -0.3f);
    spot.direction = glm::normalize(Vec3f(0.3f, -1.f, 0.2f));
    spot.intensity = I;
    spot.innerConeAngle = 0.25f;
    spot.outerConeAngle = 0.6f;
    scene.spotLights.push_back(spot);
    scene.finalize();

    const int w = 32, h = 32;
    Camera camera(*scene.camera, w, h);
    const float cosInner = std::cos(spot.innerConeAngle), cosOuter = std::cos(spot.outerConeAngle);
    double sum = 0.0;
    const int n = 8;  // n × n rays per pixel
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    Ray ray = camera.generateRay(Vec2f(float(x) + (float(i) + 0.5f) / n, float(y) + (float(j) + 0.5f) / n), Vec2f(0.5f));
                    float t = -ray.o.y / ray.d.y;
                    Vec3f p = ray.o + t * ray.d;
                    Vec3f toLight = spot.position - p;
                    float d2 = glm::dot(toLight, toLight);
                    Vec3f wi = toLight / std::sqrt(d2);
                    sum += spotFalloff(glm::dot(-wi, spot.direction), cosInner, cosOuter) * wi.y / d2;
                }
    const double meanFactor = sum / double(w * h * n * n);
    const Rgb expected = albedo * I * float(meanFactor / kPi);
    for (const char* name : {"ptnee", "lt", "bdpt"}) {
        bool lt = std::string(name) == "lt";
        Film film = render(scene, name, w, h, lt ? 256 : 16, 4);
        test::expectImageMean(film, expected, lt ? 0.01 : 0.005, name);
    }
}

// Light selection is proportional to power: a spot's power is 2π I [(1 − cos inner) + (cos inner −
// cos outer)/3] (the falloff integrated over the sphere, checked here by quadrature), a point's 4π I,
// a directional light's and the environment's measured through the scene's disk π r².
TEST(LightSelection, ProbabilitiesAreProportionalToPower) {
    Scene scene = diffusePlane(Rgb(0.5f), 1.f);
    SpotLightDesc spot;
    spot.intensity = Rgb(2.f);
    spot.innerConeAngle = 0.3f;
    spot.outerConeAngle = 0.9f;
    scene.spotLights.push_back(spot);
    scene.pointLights.push_back({Vec3f(0.f, 1.f, 0.f), Rgb(1.f)});
    scene.directionalLights.push_back({Vec3f(0.f, -1.f, 0.f), Rgb(0.5f)});
    EnvironmentDesc env;
    env.color = Rgb(0.25f);
    scene.environment = env;
    scene.finalize();
    const LightSet& lights = scene.lights();
    ASSERT_EQ(lights.size(), 4u);
    // Quadrature of the spot's falloff over the sphere.
    double spotIntegral = 0.0;
    const int steps = 200000;
    const float cosInner = std::cos(spot.innerConeAngle), cosOuter = std::cos(spot.outerConeAngle);
    for (int i = 0; i < steps; ++i) {
        double c = -1.0 + 2.0 * (i + 0.5) / steps;
        spotIntegral += spotFalloff(float(c), cosInner, cosOuter) * 2.0 * kPi * (2.0 / steps);
    }
    const double r = lights.sceneRadius();
    // LightSet order: area lights, points, spots, directional lights, the environment.
    const double power[4] = {4.0 * kPi * 1.0, 2.0 * spotIntegral, kPi * r * r * 0.5, kPi * r * r * 4.0 * kPi * 0.25};
    double total = power[0] + power[1] + power[2] + power[3];
    for (uint32_t i = 0; i < 4; ++i)
        EXPECT_NEAR(lights.pickPmf(i), power[i] / total, 1e-4 * power[i] / total + 1e-7) << "light " << i;
}

// Per-pixel agreement (Z-test over 8×8-pixel bins, tests/test_agreement.h) of ptnee, lt and bdpt on
// the Cornell box lit by a spot light through its ceiling opening's place, a pointing-down cone
// whose edge crosses the walls (`pt` cannot find a delta light and is left out).
TEST(IntegratorAgreement, SpotLitCornellBox) {
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(test::sourcePath("scenes/cornell-box/cornell-box.gltf"), warnings);
    for (Material& m : scene.materials) m.emission = Rgb(0.f);
    SpotLightDesc spot;
    spot.position = Vec3f(0.278f, 0.5f, 0.28f);
    spot.direction = glm::normalize(Vec3f(0.1f, -1.f, 0.15f));
    spot.intensity = Rgb(0.3f);
    spot.innerConeAngle = 0.4f;
    spot.outerConeAngle = 0.7f;
    scene.spotLights.push_back(spot);
    scene.finalize();
    test::expectIntegratorsAgree(scene, {{"ptnee", 16}, {"lt", 32}, {"bdpt", 8}}, 32, 32, 24);
}

namespace {

/// A 1 × 1 emitter in the plane y = `height` facing down, with texture coordinates (0..1) and an
/// emissive texture of 4 × 2 texels, nearest-filtered, whose left column is black, and the rest
/// grows brighter to the right; above a diffuse floor.
Scene texturedEmitterScene(const Image* texture) {
    Scene scene;
    Material floor, light;
    floor.bsdf.baseColor = Rgb(0.7f);
    light.bsdf.baseColor = Rgb(0.f);
    light.emission = Rgb(4.f, 3.f, 2.f);
    light.textures.emissive.image = texture;
    light.textures.emissive.filter = FilterMode::Nearest;
    scene.materials = {floor, light};
    TriangleMesh quad;
    quad.name = "floor";
    quad.positions = {{-3.f, 0.f, -3.f}, {3.f, 0.f, -3.f}, {3.f, 0.f, 3.f}, {-3.f, 0.f, 3.f}};
    quad.triangles = {{0, 2, 1}, {0, 3, 2}};
    scene.geometry.meshes.push_back(quad);
    TriangleMesh emitter;
    emitter.name = "emitter";
    emitter.materialId = 1;
    emitter.positions = {{-0.5f, 1.f, -0.5f}, {0.5f, 1.f, -0.5f}, {0.5f, 1.f, 0.5f}, {-0.5f, 1.f, 0.5f}};
    emitter.texcoords[0] = {{0.f, 0.f}, {1.f, 0.f}, {1.f, 1.f}, {0.f, 1.f}};
    emitter.triangles = {{0, 1, 2}, {0, 2, 3}};  // facing −y (down)
    scene.geometry.meshes.push_back(emitter);
    scene.finalize();
    return scene;
}

}  // namespace

// An emissive texture multiplies the emission point by point (glTF emissiveFactor × emissiveTexture)
// in every integrator's emitter evaluation, and light selection weighs each triangle by its mean
// texture value: the camera looking up at the emitter sees the texture's texels, a triangle over
// black texels is never picked, and the integrators agree on the floor it lights.
TEST(TexturedEmitter, EmissionFollowsTheTextureAndSelectionItsPower) {
    auto image = std::make_unique<Image>();
    ImageLevel level;
    level.width = 4;
    level.height = 2;
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) level.texels.push_back(x == 0 ? Vec4f(0.f, 0.f, 0.f, 1.f) : Vec4f(float(x) * 0.25f + 0.1f * y + 0.05f));
    image->levels.push_back(level);
    buildMipLevels(*image);
    Scene scene = texturedEmitterScene(image.get());
    const LightSet& lights = scene.lights();
    ASSERT_EQ(lights.size(), 2u);
    // Selection ∝ emitted power: the two triangles' mean texture values, by quadrature over each.
    auto meanOver = [&](int tri) {
        const TriangleMesh& m = scene.geometry.meshes[1];
        double sum = 0.0;
        const int n = 200;
        int count = 0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n - j; ++i) {
                float u = (float(i) + 0.33f) / n, v = (float(j) + 0.33f) / n;
                Vec2f uv = m.texcoordAt(0, uint32_t(tri), u, v);
                Vec4f t = sampleTexture(scene.materials[1].textures.emissive, uv, 0.f);
                sum += luminance(Rgb(4.f, 3.f, 2.f) * Rgb(t.r, t.g, t.b));
                ++count;
            }
        return sum / count;
    };
    double p0 = meanOver(0), p1 = meanOver(1);
    EXPECT_NEAR(lights.pickPmf(0) / lights.pickPmf(1), p0 / p1, 0.06 * p0 / p1);
    // Seen from below: the pixel under texel x shows emission × texel.
    CameraDesc cam;
    cam.cameraToWorld = glm::inverse(glm::lookAt(Vec3f(0.f, 0.2f, 0.f), Vec3f(0.f, 1.f, 0.f), Vec3f(0.f, 0.f, 1.f)));
    cam.yfov = 0.7f;
    scene.camera = cam;
    Camera camera(cam, 8, 8);
    Film film = render(scene, "ptnee", 8, 8, 4, 9, 0);
    int checked = 0;
    for (int y = 1; y < 7; ++y)
        for (int x = 1; x < 7; ++x) {
            // Where the pixel centre's ray meets the emitter, and the texel there.
            Ray ray = camera.generateRay(Vec2f(float(x) + 0.5f, float(y) + 0.5f), Vec2f(0.5f));
            Vec3f p = ray.o + ((1.f - ray.o.y) / ray.d.y) * ray.d;
            if (std::abs(p.x) > 0.45f || std::abs(p.z) > 0.45f) continue;
            float fu = (p.x + 0.5f) * 4.f, fv = (p.z + 0.5f) * 2.f;
            if (std::abs(fu - std::round(fu)) < 0.3f || std::abs(fv - std::round(fv)) < 0.3f) continue;  // texel edge
            Vec4f t = image->levels[0].at(int(fu), int(fv));
            EXPECT_NEAR(film.pixel(x, y).r, 4.f * t.r, 1e-3f) << "pixel " << x << "," << y;
            ++checked;
        }
    EXPECT_GE(checked, 4);
    // The floor under the emitter, through every strategy that finds a textured emitter.
    scene.camera = lookAtCameraDown();
    test::expectIntegratorsAgree(scene, {{"ptnee", 8}, {"pt", 32}, {"lt", 16}, {"bdpt", 4}}, 32, 32, 24);
}

// Lights inside an imported glTF asset (TESSERA_asset_gltf) come along with it, placed by the
// importing node's transform: a spot light keeps its cone, a directional light its direction.
TEST(PunctualLights, SpotAndDirectionalLightsOfAnImportedAssetAreKept) {
    std::filesystem::path dir = test::tempDir("asset-lights");
    std::filesystem::create_directories(dir / "assets" / "lamp");
    std::ofstream(dir / "assets" / "lamp" / "lamp.gltf") << R"({"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_lights_punctual"],
      "extensions": {"KHR_lights_punctual": {"lights": [
        {"type": "spot", "intensity": 2.0, "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.3}},
        {"type": "directional", "intensity": 0.5}]}},
      "scenes": [{"nodes": [0, 1]}], "scene": 0,
      "nodes": [{"translation": [0, 1, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
                {"extensions": {"KHR_lights_punctual": {"light": 1}}}]})";
    std::string scenePath = (dir / "scene.gltf").string();
    std::ofstream(scenePath) << R"({"asset": {"version": "2.0"}, "extensionsUsed": ["TESSERA_asset_gltf"],
      "scenes": [{"nodes": [0]}], "scene": 0,
      "nodes": [{"translation": [3, 0, 0], "extensions": {"TESSERA_asset_gltf": {"asset": "lamp/lamp.gltf"}}}]})";
    std::vector<std::string> warnings;
    SceneLoadOptions options;
    options.assetRoots = {(dir / "assets").string()};
    Scene scene = loadGltfScene(scenePath, warnings, options);
    ASSERT_EQ(scene.spotLights.size(), 1u);
    EXPECT_EQ(scene.spotLights[0].position, Vec3f(3.f, 1.f, 0.f));
    EXPECT_FLOAT_EQ(scene.spotLights[0].outerConeAngle, 0.3f);
    ASSERT_EQ(scene.directionalLights.size(), 1u);
    EXPECT_EQ(scene.directionalLights[0].irradiance, Rgb(0.5f));
    EXPECT_EQ(scene.lights().size(), 2u);
}
