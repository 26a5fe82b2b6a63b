// Vector, transform, frame and ray-offset basics.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "core/frame.h"
#include "core/ray.h"
#include "core/sampler.h"
#include "core/sampling.h"

using namespace tessera;

TEST(Math, TransformsComposeAndInvert) {
    Mat4f t = glm::translate(Mat4f(1.f), Vec3f(1, 2, 3));
    Mat4f r = glm::rotate(Mat4f(1.f), 0.7f, glm::normalize(Vec3f(1, 1, 0)));
    Mat4f s = glm::scale(Mat4f(1.f), Vec3f(2, 3, 4));
    Mat4f m = t * r * s;
    Vec4f p(0.3f, -1.2f, 5.f, 1.f);
    Vec4f back = glm::inverse(m) * (m * p);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(back[i], p[i], 1e-5f);
    // A point transforms with translation, a direction does not.
    EXPECT_NEAR((t * Vec4f(0, 0, 0, 1)).x, 1.f, 0.f);
    EXPECT_NEAR((t * Vec4f(1, 0, 0, 0)).x, 1.f, 0.f);
    EXPECT_NEAR(glm::dot(glm::cross(Vec3f(1, 0, 0), Vec3f(0, 1, 0)), Vec3f(0, 0, 1)), 1.f, 0.f);
}

TEST(Math, FrameIsOrthonormalForAnyNormal) {
    Pcg32 rng(7, 0);
    for (int i = 0; i < 10000; ++i) {
        Vec3f n = sampleUniformSphere(rng.next2D());
        if (i == 0) n = Vec3f(0, 0, -1);  // the branch-free basis' singular-looking case
        Frame f(n);
        EXPECT_NEAR(glm::dot(f.s, f.t), 0.f, 1e-5f);
        EXPECT_NEAR(glm::dot(f.s, f.n), 0.f, 1e-5f);
        EXPECT_NEAR(glm::length(f.s), 1.f, 1e-5f);
        EXPECT_NEAR(glm::length(f.t), 1.f, 1e-5f);
        Vec3f v = sampleUniformSphere(rng.next2D());
        Vec3f back = f.toWorld(f.toLocal(v));
        EXPECT_NEAR(glm::length(back - v), 0.f, 1e-5f);
    }
}

TEST(Math, RayOffsetLeavesTheSurfaceOnTheRequestedSide) {
    Pcg32 rng(3, 0);
    for (int i = 0; i < 10000; ++i) {
        float scale = std::pow(10.f, rng.nextFloat() * 10.f - 5.f);  // 1e-5 .. 1e5
        Vec3f p = scale * (2.f * Vec3f(rng.nextFloat(), rng.nextFloat(), rng.nextFloat()) - 1.f);
        Vec3f n = sampleUniformSphere(rng.next2D());
        Vec3f q = offsetRayOrigin(p, n);
        EXPECT_GT(glm::dot(Vec3d(q) - Vec3d(p), Vec3d(n)), 0.0) << "p=" << p.x << "," << p.y << "," << p.z;
    }
}

TEST(Math, RngIsReproducibleAndInUnitInterval) {
    Sampler a(Vec2i(3, 4), 17, 99), b(Vec2i(3, 4), 17, 99), c(Vec2i(3, 4), 18, 99);
    bool differs = false;
    for (int i = 0; i < 1000; ++i) {
        float x = a.get1D(), y = b.get1D(), z = c.get1D();
        EXPECT_EQ(x, y);
        EXPECT_GE(x, 0.f);
        EXPECT_LT(x, 1.f);
        differs |= x != z;
    }
    EXPECT_TRUE(differs);
}

TEST(Math, WarpsLandInTheirDomains) {
    Pcg32 rng(5, 0);
    for (int i = 0; i < 10000; ++i) {
        Vec2f u = rng.next2D();
        Vec3f h = sampleCosineHemisphere(u);
        EXPECT_GE(h.z, 0.f);
        EXPECT_NEAR(glm::length(h), 1.f, 1e-5f);
        Vec2f b = sampleUniformTriangle(u);
        EXPECT_GE(b.x, 0.f);
        EXPECT_GE(b.y, 0.f);
        EXPECT_LE(b.x + b.y, 1.f + 1e-6f);
    }
    EXPECT_FLOAT_EQ(powerHeuristic(1.f, 1.f), 0.5f);
    EXPECT_FLOAT_EQ(powerHeuristic(3.f, 1.f), 0.9f);
}
