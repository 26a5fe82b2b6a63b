// The environment light in every integrator: furnaces with analytic answers (a convex Lambertian
// object under a constant environment), the orientation convention, importance sampling (χ²,
// relMSE with a small sun) and agreement of the integrators on environment-lit scenes.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "integrators/integrator.h"
#include "render/renderer.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

const char* const kIntegrators[] = {"pt", "ptnee", "lt", "bdpt"};

CameraDesc lookAtCamera(Vec3f eye, Vec3f target, float yfov) {
    CameraDesc d;
    d.cameraToWorld = glm::inverse(glm::lookAt(eye, target, Vec3f(0.f, 1.f, 0.f)));
    d.yfov = yfov;
    return d;
}

/// A Lambertian sphere of radius 1 at the origin (analytic, or a closed convex UV-sphere mesh) under
/// a constant environment L.
Scene convexObjectUnderEnvironment(Rgb albedo, Rgb L, bool asMesh) {
    Scene scene;
    Material m;
    m.bsdf.baseColor = albedo;
    scene.materials.push_back(m);
    if (asMesh) scene.geometry.meshes.push_back(test::makeUvSphereMesh(Vec3f(0.f), 1.f, 24, 48, 0));
    else scene.geometry.spheres.push_back(Sphere{"ball", Vec3f(0.f), 1.f, 0});
    EnvironmentDesc env;
    env.color = L;
    env.intensity = 1.f;
    env.source = "constant";
    scene.environment = env;
    scene.finalize();
    return scene;
}

Film render(const Scene& scene, const std::string& integrator, int w, int h, int spp, uint64_t seed) {
    test::TestRender r = test::renderScene(scene, integrator, w, h, RenderOptions{.spp = spp, .seed = seed, .tileSize = 16});
    EXPECT_EQ(r.stats.nonFiniteDropped, 0u) << integrator;
    return std::move(r.film);
}

/// Image mean within 3 standard errors and `relTol` of `expected` in every channel.
void expectMean(const Film& film, Rgb expected, double relTol, const std::string& what) {
    double mean[3], se[3];
    test::pixelMean(film, mean, se);
    for (int c = 0; c < 3; ++c) {
        double err = std::abs(mean[c] - expected[c]);
        EXPECT_LE(err, 3.0 * se[c] + 1e-5 * expected[c]) << what << " channel " << c << ": mean " << mean[c] << " expected "
                                                          << expected[c] << " se " << se[c];
        EXPECT_LE(err, relTol * expected[c]) << what << " channel " << c << ": mean " << mean[c] << " expected " << expected[c] << " se " << se[c];
    }
}

int sppFor(const std::string& name) { return name == "lt" ? 8192 : name == "bdpt" ? 64 : 128; }

}  // namespace

// Every point of a convex object sees only the environment (no part of it hides another), so a
// Lambertian surface of albedo a under constant radiance L reflects exactly a·L in every direction
// (irradiance π L, BRDF a/π) and the background is L: every integrator, each through its own
// strategies (pt: escaping BSDF rays; ptnee: + environment sampling, MIS; lt: light sub-paths from
// the environment's disk, camera rays for the background; bdpt: all of them).
TEST(EnvironmentFurnace, ConvexLambertianObjectUnderAConstantEnvironment) {
    const Rgb albedo(0.5f, 0.3f, 0.8f), L(1.f, 2.f, 0.5f);
    for (bool asMesh : {false, true}) {
        Scene scene = convexObjectUnderEnvironment(albedo, L, asMesh);
        // Filling the frame: at distance 3 the sphere subtends 19.5° (19.4° for the mesh's flat
        // facets); the frame's half-diagonal is 16°.
        scene.camera = lookAtCamera(Vec3f(0.3f, 0.4f, 3.f), Vec3f(0.f), 0.4f);
        for (const char* name : kIntegrators) {
            // Light tracing lands only ~1 in 5 of its paths in this frame and splats each with a
            // varying weight: 0.5% would take 16× its 2 M paths, so it is held to 1% (and 3 SE).
            bool lt = std::string(name) == "lt";
            Film film = render(scene, name, lt ? 16 : 24, lt ? 16 : 24, sppFor(name), 11);
            expectMean(film, albedo * L, lt ? 0.01 : 0.005, std::string(name) + (asMesh ? " mesh" : " sphere") + " object");
        }
        // Looking away from it: only the environment.
        scene.camera = lookAtCamera(Vec3f(0.f, 0.f, 3.f), Vec3f(0.f, 0.5f, 6.f), 0.8f);
        for (const char* name : kIntegrators) {
            Film film = render(scene, name, 16, 16, 4, 12);
            expectMean(film, L, 1e-5, std::string(name) + " background");
        }
    }
}
