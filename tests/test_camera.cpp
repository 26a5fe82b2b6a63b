// Camera round trip: a world point projects to the pixel whose ray passes through it.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "core/rng.h"
#include "scene/camera.h"

using namespace tessera;

namespace {
double distancePointToRay(const Vec3f& p, const Ray& r) {
    Vec3d d = glm::normalize(Vec3d(r.d)), op = Vec3d(p) - Vec3d(r.o);
    return glm::length(op - glm::dot(op, d) * d);
}
}  // namespace

TEST(Camera, WorldPointProjectsToThePixelWhoseRayHitsIt) {
    CameraDesc d;
    d.cameraToWorld = glm::inverse(glm::lookAt(Vec3f(1, 2, 5), Vec3f(0, 0.5f, 0), Vec3f(0, 1, 0)));
    d.yfov = 0.8f;
    Camera cam(d, 320, 240);
    Pcg32 rng(11, 0);
    int tested = 0;
    for (int i = 0; i < 2000; ++i) {
        Vec3f p = Vec3f(rng.nextFloat(), rng.nextFloat(), rng.nextFloat()) * 4.f - 2.f;
        Vec2f raster;
        if (!cam.worldToRaster(p, raster)) continue;
        ++tested;
        Ray ray = cam.generateRay(raster, Vec2f(0.5f));
        double dist = glm::length(Vec3d(p) - Vec3d(ray.o));
        EXPECT_LT(distancePointToRay(p, ray), 1e-5 * dist + 1e-6);
        EXPECT_GT(glm::dot(p - ray.o, ray.d), 0.f);
    }
    EXPECT_GT(tested, 500);
}

TEST(Camera, RasterCentreLooksForwardAndCornersSpanTheFov) {
    CameraDesc d;  // identity transform: eye at origin looking down -z
    d.yfov = 1.0f;
    Camera cam(d, 200, 100);
    Ray c = cam.generateRay(Vec2f(100, 50), Vec2f(0.5f));
    EXPECT_NEAR(c.d.z, -1.f, 1e-6f);
    Ray top = cam.generateRay(Vec2f(100, 0), Vec2f(0.5f));
    EXPECT_NEAR(std::atan2(top.d.y, -top.d.z), 0.5f, 1e-5f);  // half the vertical fov, y up
    Ray right = cam.generateRay(Vec2f(200, 50), Vec2f(0.5f));
    EXPECT_NEAR(right.d.y, 0.f, 1e-6f);
    EXPECT_GT(right.d.x, 0.f);
    EXPECT_NEAR(right.d.x / -right.d.z, 2.f * std::tan(0.5f), 1e-5f);  // aspect 2
}

TEST(Camera, ThinLensRaysConvergeOnTheFocusPlane) {
    CameraDesc d;
    d.yfov = 0.7f;
    d.apertureRadius = 0.2f;
    d.focusDistance = 3.f;
    Camera cam(d, 64, 64);
    Pcg32 rng(1, 0);
    Vec2f raster(10.3f, 50.7f);
    Ray pin = cam.generateRay(raster, Vec2f(0.5f));  // lens centre = pinhole ray
    Vec3f focus = pin.o + pin.d * (3.f / -pin.d.z);
    for (int i = 0; i < 100; ++i) {
        Ray r = cam.generateRay(raster, rng.next2D());
        float t = (focus.z - r.o.z) / r.d.z;
        EXPECT_LT(glm::length(r.o + t * r.d - focus), 1e-5f);
        EXPECT_NEAR(r.o.z, 0.f, 1e-6f);
    }
}
