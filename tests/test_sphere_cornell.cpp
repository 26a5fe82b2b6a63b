// The sphere Cornell box: radius-1e4 walls must show no acne (self-hits after spawning) and no leaks
// (rays from inside the box escaping through the seams between walls).
#include <gtest/gtest.h>

#include "accel/accel.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "scene/gltf_loader.h"
#include "test_helpers.h"

using namespace tessera;

TEST(SphereCornell, NoAcneNoLeaksOnRandomPaths) {
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(test::sourcePath("scenes/sphere-cornell/sphere-cornell.gltf"), warnings);
    auto accel = createAccel("embree", scene.geometry);
    Camera camera(*scene.camera, 160, 120);
    Pcg32 rng(2024, 0);
    int acne = 0, leaks = 0, segments = 0;
    for (int path = 0; path < 20000; ++path) {
        Ray ray = camera.generateRay(Vec2f(rng.nextFloat() * 160.f, rng.nextFloat() * 120.f), Vec2f(0.5f));
        for (int bounce = 0; bounce < 8; ++bounce) {
            Hit hit;
            ++segments;
            if (!accel->intersect(ray, hit)) {
                ++leaks;
                break;
            }
            SurfaceInteraction si = scene.interaction(ray, hit);
            // Bounce into the hemisphere on the side the ray arrived from.
            Vec3f n = glm::dot(si.ng, ray.d) < 0.f ? si.ng : -si.ng;
            Vec3f d = sampleUniformSphere(rng.next2D());
            if (glm::dot(d, n) < 0.f) d = -d;
            Ray next = spawnRay(si.p, si.ng, d);
            Hit again;
            // Acne: the spawned ray re-hits the surface it left at a tiny distance.
            if (accel->intersect(next, again) && again.geomId == hit.geomId && again.primId == hit.primId &&
                again.t < 1e-2f)
                ++acne;
            ray = next;
        }
    }
    EXPECT_EQ(acne, 0) << "of " << segments << " segments";
    EXPECT_EQ(leaks, 0) << "of " << segments << " segments";
}

TEST(SphereCornell, ShadowRaysBetweenWallPointsAreNotSelfOccluded) {
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(test::sourcePath("scenes/sphere-cornell/sphere-cornell.gltf"), warnings);
    auto accel = createAccel("embree", scene.geometry);
    // Floor point to ceiling point straight above it (nothing in between when away from the balls).
    Ray down{Vec3f(40.f, 0.f, -100.f), Vec3f(0, -1, 0)}, up{Vec3f(40.f, 0.f, -100.f), Vec3f(0, 1, 0)};
    Hit hf, hc;
    ASSERT_TRUE(accel->intersect(down, hf));
    ASSERT_TRUE(accel->intersect(up, hc));
    SurfaceInteraction a = scene.interaction(down, hf), b = scene.interaction(up, hc);
    // The hit points lie on their radius-1e4 spheres to float precision.
    for (auto [si, hit] : {std::pair{a, hf}, std::pair{b, hc}}) {
        const Sphere& s = scene.geometry.spheres[hit.primId];
        EXPECT_NEAR(glm::length(Vec3d(si.p) - Vec3d(s.center)), double(s.radius), 2e-3);
    }
    EXPECT_FALSE(accel->occluded(spawnShadowRay(a.p, a.ng, b.p, b.ng)));
}
