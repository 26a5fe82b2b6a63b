// Beer–Lambert absorption inside KHR_materials_volume bodies (integrators/volume.h) in every
// integrator: an analytic cube of index-matched glass (ior 1: no reflection, no bending) in front of
// a constant environment, the symmetry of the segment rule, and the agreement of pt, ptnee and bdpt
// on a rough absorbing sphere, where BDPT builds the same inside segments by walks and connections.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>

#include "integrators/path_vertex.h"
#include "integrators/volume.h"
#include "materials/bsdf.h"
#include "render/renderer.h"
#include "test_agreement.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

const Rgb kEnvL(1.5f, 1.f, 0.75f);
const Rgb kAttenuationColor(0.8f, 0.5f, 0.2f);
constexpr float kAttenuationDistance = 0.7f;

/// KHR_materials_volume's σa = −ln(attenuationColor) / attenuationDistance, as the loader computes it.
Rgb sigmaOf(Rgb color, float distance) {
    Rgb s;
    for (int c = 0; c < 3; ++c) s[c] = -std::log(color[c]) / distance;
    return s;
}

/// A transmissive volume material: transmission 1, the given ior and roughness, not thin-walled.
Material volumeMaterial(float ior, float roughness, Rgb sigma) {
    Material m;
    m.name = "volume";
    m.bsdf.baseColor = Rgb(1.f);
    m.bsdf.transmission = 1.f;
    m.bsdf.ior = ior;
    m.bsdf.alpha = roughness * roughness;
    m.bsdf.thinWalled = false;
    m.bsdf.attenuationCoeff = sigma;
    finalizeBsdfParams(m.bsdf);
    return m;
}

/// An axis-aligned cube of side `side` centred at the origin, triangles wound counter-clockwise seen
/// from outside (outward geometric normals, as glTF volumes require).
TriangleMesh makeCube(float side, uint32_t material) {
    TriangleMesh m;
    m.name = "cube";
    m.materialId = material;
    float h = 0.5f * side;
    // Each face: its outward axis n and two tangents (t, b) with t × b = n.
    const Vec3f faces[6][3] = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},  {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
                               {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}},  {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
                               {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},  {{0, 0, -1}, {0, 1, 0}, {1, 0, 0}}};
    for (const auto& f : faces) {
        uint32_t base = uint32_t(m.positions.size());
        Vec3f n = f[0] * h, t = f[1] * h, b = f[2] * h;
        m.positions.push_back(n - t - b);
        m.positions.push_back(n + t - b);
        m.positions.push_back(n + t + b);
        m.positions.push_back(n - t + b);
        m.triangles.emplace_back(base, base + 1, base + 2);
        m.triangles.emplace_back(base, base + 2, base + 3);
    }
    return m;
}

void setConstantEnvironment(Scene& scene, Rgb L) {
    EnvironmentDesc env;
    env.color = L;
    env.intensity = 1.f;
    env.source = "constant";
    scene.environment = env;
}

constexpr float kEyeDistance = 10.f;
constexpr float kYfov = 0.22f;

/// The index-matched cube of side 1 seen face-on from (0, 0, 10) under a constant environment.
Scene cubeScene(Rgb sigma) {
    Scene scene;
    scene.materials.push_back(volumeMaterial(1.f, 0.f, sigma));
    scene.geometry.meshes.push_back(makeCube(1.f, 0));
    setConstantEnvironment(scene, kEnvL);
    CameraDesc cam;
    cam.cameraToWorld = glm::inverse(glm::lookAt(Vec3f(0.f, 0.f, kEyeDistance), Vec3f(0.f), Vec3f(0.f, 1.f, 0.f)));
    cam.yfov = kYfov;
    scene.camera = cam;
    scene.finalize();
    return scene;
}

}  // namespace

// Scenes without an absorbing volume skip the bidirectional connections' per-segment test
// (Scene::hasVolumes): it must see a volume material, and nothing else.
TEST(VolumeAttenuation, SceneKnowsWhetherItHasAVolume) {
    EXPECT_TRUE(cubeScene(sigmaOf(kAttenuationColor, kAttenuationDistance)).hasVolumes());
    EXPECT_FALSE(cubeScene(Rgb(0.f)).hasVolumes()) << "sigma_a = 0 attenuates nothing";
    Scene thin = cubeScene(Rgb(0.5f));
    thin.materials[0].bsdf.thinWalled = true;  // KHR_materials_volume thickness 0: a surface, no volume
    thin.finalize();
    EXPECT_FALSE(thin.hasVolumes());
}

// The rule is one function of the two ends, each tested looking away from itself: the same
// segment gets the same transmittance from either end, only on the back side of a volume's
// surface, and the σa = 0 / thin-walled cases report "not attenuating" (callers multiply nothing).
TEST(VolumeAttenuation, SegmentRuleIsSymmetricAndOnlyInside) {
    const Rgb sigma = sigmaOf(kAttenuationColor, kAttenuationDistance);
    Material vol = volumeMaterial(1.5f, 0.3f, sigma);
    Scene scene = cubeScene(sigma);  // the context the rule reads emitters from (none here)
    std::unique_ptr<Accel> accel = createAccel("embree", scene.geometry);
    Camera camera(*scene.camera, 8, 8);
    const RenderContext ctx{scene, *accel, camera};
    PathVertex a, b;
    a.type = b.type = VertexType::Surface;
    a.bsdf = b.bsdf = vol.bsdf;
    a.p = Vec3f(0.f, 0.f, 0.5f);   // front face of a unit cube, normal +z
    a.ng = a.ns = Vec3f(0.f, 0.f, 1.f);
    b.p = Vec3f(0.f, 0.2f, -0.5f);  // back face, normal −z
    b.ng = b.ns = Vec3f(0.f, 0.f, -1.f);
    bool attAB = false, attBA = false;
    Rgb tAB = segmentTransmittance(ctx, a, b, attAB), tBA = segmentTransmittance(ctx, b, a, attBA);
    EXPECT_TRUE(attAB && attBA);
    float len = glm::length(b.p - a.p);
    for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(tAB[c], tBA[c]);
        EXPECT_NEAR(tAB[c], std::exp(-sigma[c] * len), 1e-6f);
    }
    // Only one end on a volume (the other a camera): still attenuated, from either side.
    PathVertex cam;
    cam.type = VertexType::Camera;
    cam.p = Vec3f(0.f, 0.f, 0.1f);  // inside the body
    cam.ng = Vec3f(0.f, 0.f, -1.f);
    Rgb tCam = segmentTransmittance(ctx, cam, b, attAB), tCam2 = segmentTransmittance(ctx, b, cam, attBA);
    EXPECT_TRUE(attAB && attBA);
    EXPECT_EQ(tCam, tCam2);
    EXPECT_NEAR(tCam[2], std::exp(-sigma[2] * glm::length(b.p - cam.p)), 1e-6f);
    // Outside the body (front side of both normals): nothing.
    PathVertex out;
    out.type = VertexType::Surface;
    out.bsdf = vol.bsdf;
    out.p = Vec3f(0.f, 0.f, 3.f);
    out.ng = out.ns = Vec3f(0.f, 0.f, -1.f);  // faces the cube: a is seen on its front side
    Rgb tOut = segmentTransmittance(ctx, a, out, attAB);
    EXPECT_FALSE(attAB);
    EXPECT_EQ(tOut, Rgb(1.f));
    // Towards infinity from inside: attenuating channels vanish, the others pass.
    PathVertex inf;
    inf.type = VertexType::Light;
    inf.atInfinity = true;
    inf.ng = Vec3f(0.f, 0.f, -1.f);
    Rgb partial = sigma;
    partial[1] = 0.f;
    a.bsdf.attenuationCoeff = partial;
    Rgb tInf = segmentTransmittance(ctx, a, inf, attAB);
    EXPECT_TRUE(attAB);
    EXPECT_EQ(tInf, Rgb(0.f, 1.f, 0.f));
    // Thin-walled or σa = 0: not a volume.
    a.bsdf.attenuationCoeff = sigma;
    a.bsdf.thinWalled = true;
    b.bsdf.thinWalled = true;
    segmentTransmittance(ctx, a, b, attAB);
    EXPECT_FALSE(attAB);
    a.bsdf.thinWalled = b.bsdf.thinWalled = false;
    a.bsdf.attenuationCoeff = b.bsdf.attenuationCoeff = Rgb(0.f);
    segmentTransmittance(ctx, a, b, attAB);
    EXPECT_FALSE(attAB);
}

// A point sampled on an emitter that is itself a volume's boundary (a light sub-path's origin, a
// next-event sample) is an end like a surface hit on it: the segment from it into the body is
// attenuated, the segment from it outwards is not.
TEST(VolumeAttenuation, EmitterOnAVolumeBoundaryIsAnEnd) {
    const Rgb sigma = sigmaOf(kAttenuationColor, kAttenuationDistance);
    Scene scene = cubeScene(sigma);
    scene.materials[0].emission = Rgb(1.f);
    scene.finalize();
    ASSERT_FALSE(scene.lights().empty());
    std::unique_ptr<Accel> accel = createAccel("embree", scene.geometry);
    Camera camera(*scene.camera, 8, 8);
    const RenderContext ctx{scene, *accel, camera};
    // Light 0 is the first triangle of the +x face: its normal is +x.
    PathVertex light;
    light.type = VertexType::Light;
    light.lightIndex = 0;
    light.p = Vec3f(0.5f, 0.1f, 0.1f);
    light.ng = light.ns = Vec3f(1.f, 0.f, 0.f);
    PathVertex inner;
    inner.type = VertexType::Camera;  // not a surface: only the light end can qualify
    inner.p = Vec3f(-0.2f, 0.1f, 0.1f);
    bool att = false;
    Rgb t = segmentTransmittance(ctx, light, inner, att);
    EXPECT_TRUE(att);
    EXPECT_NEAR(t[1], std::exp(-sigma[1] * 0.7f), 1e-5f);
    EXPECT_EQ(t, segmentTransmittance(ctx, inner, light, att));
    inner.p = Vec3f(2.f, 0.1f, 0.1f);
    segmentTransmittance(ctx, light, inner, att);
    EXPECT_FALSE(att);
    EXPECT_EQ(emitterVolumeSigma(scene, 0, light.ng, Vec3f(-1.f, 0.f, 0.f)), sigma);
}

// Index-matched glass (ior 1, roughness 0, transmission 1): every camera ray through the cube goes
// straight through, so a pixel through it is exactly L·exp(−σa·d) = L·c^(d/D), d the chord (the
// side over the cosine to the view axis: face-on, d ≈ side). Pixels off the cube see L. pt, ptnee
// and bdpt must all give it (lt cannot: the cube is a delta surface seen by the camera).
TEST(VolumeAttenuation, IndexMatchedCubeIsBeerLambertExact) {
    const Rgb sigma = sigmaOf(kAttenuationColor, kAttenuationDistance);
    Scene scene = cubeScene(sigma);
    const int W = 32;
    const float tanHalf = std::tan(0.5f * kYfov);
    for (const char* name : {"pt", "ptnee", "bdpt"}) {
        test::TestRender r = test::renderScene(scene, name, W, W, RenderOptions{.spp = 4, .seed = 11, .tileSize = 16});
        EXPECT_EQ(r.stats.nonFiniteDropped, 0u) << name;
        int inside = 0, outside = 0;
        for (int y = 0; y < W; ++y)
            for (int x = 0; x < W; ++x) {
                // Pixel-centre direction (camera looks down −z); the chord is taken at its centre.
                float dx = (2.f * (float(x) + 0.5f) / float(W) - 1.f) * tanHalf;
                float dy = (1.f - 2.f * (float(y) + 0.5f) / float(W)) * tanHalf;
                float pixel = 2.f * tanHalf / float(W);
                // Where the pixel's rays cross the back face (z = −0.5) and the front face (z = 0.5),
                // the cube's silhouette from the eye.
                float reachBack = (kEyeDistance + 0.5f) * (std::max(std::abs(dx), std::abs(dy)) + pixel);
                float farFront = (kEyeDistance - 0.5f) * (std::max(std::abs(dx), std::abs(dy)) - pixel);
                Rgb v = r.film.pixel(x, y);
                if (reachBack < 0.5f) {
                    ++inside;
                    float d = std::sqrt(1.f + dx * dx + dy * dy);  // side 1 over cos θ
                    for (int c = 0; c < 3; ++c) {
                        float expected = kEnvL[c] * std::pow(kAttenuationColor[c], d / kAttenuationDistance);
                        EXPECT_NEAR(v[c], expected, 1e-3f * expected) << name << " pixel " << x << "," << y << " channel " << c;
                    }
                } else if (farFront > 0.5f) {
                    ++outside;
                    for (int c = 0; c < 3; ++c) EXPECT_NEAR(v[c], kEnvL[c], 1e-5f) << name << " pixel " << x << "," << y;
                }
            }
        EXPECT_GT(inside, 100) << name;
        EXPECT_GT(outside, 50) << name;
    }
}

// A rough (roughness 0.6) ior 1.5 absorbing sphere on a diffuse floor under a dim constant
// environment, with an emitting sphere inside it: light leaves the emitter inside the body, is
// refracted out (or totally reflected back), and BDPT builds the inside segments by camera walks,
// light walks, NEE segments from the inner surface to the emitter and connection edges between two
// inside vertices; ptnee by traced rays and shadow segments; pt by traced rays only. They must agree
// bin by bin (batch-binned two-sample test, Šidák-corrected): a strategy that left T out of its
// segments would disagree.
TEST(VolumeAttenuation, RoughAbsorbingSphereIntegratorsAgree) {
    Scene scene;
    const Rgb sigma = sigmaOf(Rgb(0.3f, 0.6f, 0.9f), 0.5f);
    scene.materials.push_back(volumeMaterial(1.5f, 0.6f, sigma));
    Material floor;
    floor.name = "floor";
    floor.bsdf.baseColor = Rgb(0.6f);
    floor.bsdf.specular = 0.f;
    finalizeBsdfParams(floor.bsdf);
    scene.materials.push_back(floor);
    Material emitter;
    emitter.name = "emitter";
    emitter.bsdf.baseColor = Rgb(0.f);
    emitter.bsdf.specular = 0.f;
    finalizeBsdfParams(emitter.bsdf);
    emitter.emission = Rgb(6.f);
    scene.materials.push_back(emitter);
    scene.geometry.meshes.push_back(test::makeUvSphereMesh(Vec3f(0.f, 1.f, 0.f), 1.f, 16, 32, 0));
    scene.geometry.meshes.push_back(test::makeUvSphereMesh(Vec3f(0.f, 1.f, 0.f), 0.35f, 8, 16, 2));
    TriangleMesh quad;
    quad.name = "floor";
    quad.materialId = 1;
    quad.positions = {Vec3f(-4.f, 0.f, -4.f), Vec3f(-4.f, 0.f, 4.f), Vec3f(4.f, 0.f, 4.f), Vec3f(4.f, 0.f, -4.f)};
    quad.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.geometry.meshes.push_back(quad);
    setConstantEnvironment(scene, Rgb(0.2f));
    CameraDesc cam;
    cam.cameraToWorld = glm::inverse(glm::lookAt(Vec3f(0.f, 2.f, 4.f), Vec3f(0.f, 0.9f, 0.f), Vec3f(0.f, 1.f, 0.f)));
    cam.yfov = 0.5f;
    scene.camera = cam;
    scene.finalize();
    test::expectIntegratorsAgree(scene, {{"ptnee", 64}, {"pt", 128}, {"bdpt", 32}}, 24, 24, 16, 8);
}
