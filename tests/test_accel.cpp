// Embree against brute force, ray by ray: the same hit/miss, ids, t, (u, v) and normal.
#include <gtest/gtest.h>

#include "accel/accel.h"
#include "core/error.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "scene/gltf_loader.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

struct Mismatch {
    int rays = 0, hitMiss = 0, idDiff = 0, tDiff = 0, uvDiff = 0, normalDiff = 0;
};

/// Random rays: origins inside the scene's (padded) bounds, uniform directions; a third aimed at
/// random points of the geometry so most rays hit.
Mismatch compareBackends(const SceneGeometry& g, int nRays, uint64_t seed, float tRelTol) {
    auto embree = createAccel("embree", g);
    auto brute = createAccel("brute", g);
    Bounds3f b = g.bounds();
    Vec3f ext = b.diagonal();
    Pcg32 rng(seed, 0);
    Mismatch m;
    for (int i = 0; i < nRays; ++i) {
        Vec3f u(rng.nextFloat(), rng.nextFloat(), rng.nextFloat());
        Ray ray;
        ray.o = b.lower - 0.25f * ext + 1.5f * ext * u;
        if (i % 3 == 0) {
            Vec3f target = b.lower + ext * Vec3f(rng.nextFloat(), rng.nextFloat(), rng.nextFloat());
            ray.d = glm::normalize(target - ray.o);
        } else {
            ray.d = sampleUniformSphere(rng.next2D());
        }
        Hit he, hb;
        bool e = embree->intersect(ray, he), br = brute->intersect(ray, hb);
        EXPECT_EQ(e, embree->occluded(ray));
        EXPECT_EQ(br, brute->occluded(ray));
        ++m.rays;
        if (e != br) { ++m.hitMiss; continue; }
        if (!e) continue;
        if (he.geomId != hb.geomId || he.primId != hb.primId) {
            // An edge or vertex shared by two primitives: both are right if they agree on t.
            if (std::abs(he.t - hb.t) > tRelTol * std::max(1.f, hb.t)) ++m.idDiff;
            continue;
        }
        if (std::abs(he.t - hb.t) > tRelTol * std::max(1.f, hb.t)) ++m.tDiff;
        if (std::abs(he.u - hb.u) > 1e-3f || std::abs(he.v - hb.v) > 1e-3f) ++m.uvDiff;
        if (glm::dot(he.ng, hb.ng) < 0.9999f) ++m.normalDiff;
    }
    return m;
}

}  // namespace

TEST(Accel, EmbreeMatchesBruteForceOnATriangleMesh) {
    SceneGeometry g;
    g.meshes.push_back(test::makeUvSphereMesh(Vec3f(0), 1.f, 24, 48, 0));
    g.meshes.push_back(test::makeUvSphereMesh(Vec3f(1.5f, 0.2f, -0.3f), 0.6f, 12, 24, 0));
    // A random triangle soup overlapping both.
    TriangleMesh soup;
    Pcg32 rng(42, 0);
    for (int i = 0; i < 300; ++i) {
        Vec3f c = Vec3f(rng.nextFloat(), rng.nextFloat(), rng.nextFloat()) * 3.f - 1.5f;
        for (int k = 0; k < 3; ++k) soup.positions.push_back(c + 0.3f * (Vec3f(rng.nextFloat(), rng.nextFloat(), rng.nextFloat()) - 0.5f));
        soup.triangles.emplace_back(3 * i, 3 * i + 1, 3 * i + 2);
    }
    g.meshes.push_back(soup);
    Mismatch m = compareBackends(g, 20000, 1, 1e-5f);
    // Watertight (brute force) and Möller (Embree) tests may disagree only on rays that graze an
    // edge within float precision: a handful in 20k random rays at most.
    EXPECT_LE(m.hitMiss, 2);
    EXPECT_EQ(m.idDiff, 0);
    EXPECT_EQ(m.tDiff, 0);
    EXPECT_EQ(m.uvDiff, 0);
    EXPECT_EQ(m.normalDiff, 0);
}

// Embree's backend tests a scene's spheres itself after Embree's triangle query when there are
// few of them, and hands them to Embree as user geometry when there are many
// (EmbreeAccel::kDirectSphereCount): spheres among triangles, on both sides of that count, must give
// brute force's records, closest hit and occlusion alike.
TEST(Accel, EmbreeMatchesBruteForceOnSpheresAmongTrianglesFewOrMany) {
    for (int nSpheres : {1, 3, 16, 17, 40}) {
        SceneGeometry g;
        g.meshes.push_back(test::makeUvSphereMesh(Vec3f(0), 1.f, 12, 24, 0));
        Pcg32 rng(uint64_t(nSpheres), 0);
        for (int i = 0; i < nSpheres; ++i) {
            Vec3f c = Vec3f(rng.nextFloat(), rng.nextFloat(), rng.nextFloat()) * 4.f - 2.f;
            g.spheres.push_back(Sphere{"s" + std::to_string(i), c, 0.1f + 0.5f * rng.nextFloat(), 0});
        }
        Mismatch m = compareBackends(g, 20000, 7, 1e-5f);
        EXPECT_LE(m.hitMiss, 2) << nSpheres << " spheres";
        EXPECT_EQ(m.idDiff, 0) << nSpheres << " spheres";
        EXPECT_EQ(m.tDiff, 0) << nSpheres << " spheres";
        EXPECT_EQ(m.uvDiff, 0) << nSpheres << " spheres";
        EXPECT_EQ(m.normalDiff, 0) << nSpheres << " spheres";
    }
}

TEST(Accel, EmbreeMatchesBruteForceOnSpheresIncludingRadius1e4) {
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(test::sourcePath("scenes/sphere-cornell/sphere-cornell.gltf"), warnings);
    ASSERT_EQ(scene.geometry.spheres.size(), 9u);
    // The box is what matters: origins around it (the walls' own bounds are 2e4 wide).
    Bounds3f box;
    box.lower = Vec3f(-60, -50, -240);
    box.upper = Vec3f(60, 50, 20);
    auto embree = createAccel("embree", scene.geometry);
    auto brute = createAccel("brute", scene.geometry);
    Pcg32 rng(9, 0);
    int disagreements = 0, hits = 0;
    for (int i = 0; i < 20000; ++i) {
        Ray ray;
        ray.o = box.lower + box.diagonal() * Vec3f(rng.nextFloat(), rng.nextFloat(), rng.nextFloat());
        ray.d = sampleUniformSphere(rng.next2D());
        Hit he, hb;
        bool e = embree->intersect(ray, he), b = brute->intersect(ray, hb);
        if (e != b || (e && (he.primId != hb.primId || std::abs(he.t - hb.t) > 1e-5f * hb.t ||
                             glm::dot(he.ng, hb.ng) < 0.9999f)))
            ++disagreements;
        hits += e;
    }
    EXPECT_EQ(disagreements, 0);
    EXPECT_GT(hits, 19000);  // a closed box: almost every ray from inside hits something
}

TEST(Accel, DegenerateRaysNeverHit) {
    SceneGeometry g;
    g.meshes.push_back(test::makeUvSphereMesh(Vec3f(0), 1.f, 8, 16, 0));
    g.spheres.push_back(Sphere{"s", Vec3f(3, 0, 0), 1.f, 0});
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = kInfinity;
    std::vector<Ray> bad = {
        Ray{Vec3f(0, 0, -5), Vec3f(0, 0, 0)},     Ray{Vec3f(nan, 0, -5), Vec3f(0, 0, 1)},
        Ray{Vec3f(0, 0, -5), Vec3f(0, nan, 1)},   Ray{Vec3f(inf, 0, -5), Vec3f(0, 0, 1)},
        Ray{Vec3f(0, 0, -5), Vec3f(0, 0, inf)},   Ray{Vec3f(0, 0, -5), Vec3f(0, 0, 1), 2.f, 1.f},
    };
    for (const std::string& name : accelNames()) {
        auto accel = createAccel(name, g);
        for (const Ray& r : bad) {
            Hit h;
            EXPECT_FALSE(accel->intersect(r, h)) << name;
            EXPECT_FALSE(accel->occluded(r)) << name;
        }
        // ±0.0 direction components are legal and must work.
        Hit h;
        EXPECT_TRUE(accel->intersect(Ray{Vec3f(0, 0, -5), Vec3f(-0.f, 0.f, 1.f)}, h)) << name;
        EXPECT_NEAR(h.t, 4.f, 1e-3f) << name;
    }
}

// isTraceableRay against its definition, one coordinate at a time: every component of o and d
// (each vector lane) set to ±inf, NaN, ±0, a denormal or the largest float, tMin/tMax in every order
// with infinities and NaN, and seeded random rays.
TEST(Accel, TraceableRayPredicateMatchesItsDefinition) {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = kInfinity, big = std::numeric_limits<float>::max();
    auto definition = [](const Ray& r) {
        bool finite = true, nonZero = false;
        for (int i = 0; i < 3; ++i) {
            finite = finite && std::isfinite(r.o[i]) && std::isfinite(r.d[i]);
            nonZero = nonZero || r.d[i] != 0.f;
        }
        return finite && nonZero && r.tMin <= r.tMax;
    };
    const float values[] = {0.f, -0.f, 1.f, -2.5f, 1e-40f, big, -big, inf, -inf, nan};
    int checked = 0;
    for (int component = 0; component < 6; ++component)
        for (float v : values)
            for (float tMin : {0.f, 1.f, -inf, nan})
                for (float tMax : {0.5f, 1.f, inf, nan}) {
                    Ray r{Vec3f(0.3f, -0.2f, 5.f), Vec3f(0.f, 1.f, 0.f), tMin, tMax};
                    (component < 3 ? r.o : r.d)[component % 3] = v;
                    ASSERT_EQ(isTraceableRay(r), definition(r)) << "component " << component << " value " << v << " t " << tMin << " " << tMax;
                    ++checked;
                }
    Pcg32 rng(11, 5);
    for (int k = 0; k < 10000; ++k) {
        auto coordinate = [&] { return rng.nextFloat() < 0.05f ? values[rng.nextU32() % 10] : (rng.nextFloat() - 0.5f) * 100.f; };
        Ray r{Vec3f(coordinate(), coordinate(), coordinate()), Vec3f(coordinate(), coordinate(), coordinate()), coordinate(), coordinate()};
        ASSERT_EQ(isTraceableRay(r), definition(r)) << k;
        ++checked;
    }
    EXPECT_EQ(checked, 6 * 10 * 16 + 10000);
}

TEST(Accel, EmptySceneAndUnknownName) {
    SceneGeometry g;
    auto accel = createAccel("embree", g);
    Hit h;
    EXPECT_FALSE(accel->intersect(Ray{Vec3f(0), Vec3f(0, 0, 1)}, h));
    EXPECT_THROW(createAccel("octree", g), InputError);
}
