#pragma once
// Procedural scenes that break acceleration structures (after Embree's verify.cpp): coplanar and
// duplicated triangles, slivers, scene-spanning and tiny triangles, triangles in candidate split
// planes, spheres mixed with triangles. The battery both our BVH and our k-d tree are tested on.
#include <algorithm>
#include <string>

#include "core/rng.h"
#include "scene/scene.h"
#include "test_helpers.h"

namespace tessera::test {

inline void addTriangle(TriangleMesh& m, Vec3f a, Vec3f b, Vec3f c) {
    uint32_t i = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), {a, b, c});
    m.triangles.emplace_back(i, i + 1, i + 2);
}

inline SceneGeometry withMesh(TriangleMesh m) {
    if (m.name.empty()) m.name = "procedural";
    SceneGeometry g;
    g.meshes.push_back(std::move(m));
    return g;
}

/// One triangle in z = 0.
inline SceneGeometry singleTriangle() {
    TriangleMesh m;
    addTriangle(m, Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0));
    return withMesh(m);
}

/// A flat 40×40 quad grid in z = 0: the root cell has no extent in z.
inline SceneGeometry coplanarGrid() {
    TriangleMesh m;
    const int n = 40;
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x) m.positions.push_back(Vec3f(float(x), float(y), 0.f) / float(n));
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            uint32_t i = uint32_t(y * (n + 1) + x);
            m.triangles.emplace_back(i, i + 1, i + n + 2);
            m.triangles.emplace_back(i, i + n + 2, i + n + 1);
        }
    return withMesh(m);
}

/// A UV sphere with every triangle twice, and the whole mesh again as a second geometry.
inline SceneGeometry duplicatedTriangles() {
    SceneGeometry g;
    TriangleMesh m = makeUvSphereMesh(Vec3f(0), 1.f, 10, 20, 0);
    size_t n = m.triangles.size();
    for (size_t i = 0; i < n; ++i) m.triangles.push_back(m.triangles[i]);
    g.meshes.push_back(m);
    g.meshes.push_back(m);
    return g;
}

/// Long thin triangles (10 units by 1e-4) in random directions: they straddle most planes.
inline SceneGeometry longSlivers(int count = 400) {
    TriangleMesh m;
    Pcg32 rng(3, 0);
    for (int i = 0; i < count; ++i) {
        Vec3f a(rng.nextFloat(), rng.nextFloat(), rng.nextFloat());
        Vec3f dir = glm::normalize(Vec3f(rng.nextFloat(), rng.nextFloat(), rng.nextFloat()) - 0.5f);
        addTriangle(m, a - 5.f * dir, a + 5.f * dir, a + Vec3f(1e-4f, 2e-4f, -1e-4f));
    }
    return withMesh(m);
}

/// A small sphere under three huge triangles spanning the whole scene.
inline SceneGeometry sceneSpanningTriangles() {
    SceneGeometry g;
    g.meshes.push_back(makeUvSphereMesh(Vec3f(0), 0.3f, 12, 24, 0));
    TriangleMesh big;
    big.name = "big";
    addTriangle(big, Vec3f(-100, -1, -100), Vec3f(100, -1, -100), Vec3f(0, -1, 100));
    addTriangle(big, Vec3f(-100, -100, 2), Vec3f(100, 50, 2), Vec3f(0, 100, 2.5f));
    addTriangle(big, Vec3f(-3, -100, -100), Vec3f(-3, 100, -100), Vec3f(-3, 0, 100));
    g.meshes.push_back(big);
    return g;
}

/// Axis-aligned triangles at k/32 on every axis: they lie exactly on candidate planes.
inline SceneGeometry axisAlignedTriangles() {
    TriangleMesh m;
    for (int axis = 0; axis < 3; ++axis)
        for (int k = 0; k <= 32; ++k) {
            float c = float(k) / 32.f;
            Vec3f a(0.f), b(0.f), d(0.f);
            int u = (axis + 1) % 3, v = (axis + 2) % 3;
            a[axis] = b[axis] = d[axis] = c;
            a[u] = 0.1f, a[v] = 0.1f;
            b[u] = 0.9f, b[v] = 0.1f;
            d[u] = 0.5f, d[v] = 0.9f;
            addTriangle(m, a, b, d);
        }
    return withMesh(m);
}

/// An integer lattice of axis-aligned triangles: on each of the 17 planes x, y, z = 0, 1, …, 16, random
/// right triangles with integer vertices (legs 1–4) that overlap one another; every vertex lies on a
/// plane a binned or sweeping builder considers, and most rays hit two or more coplanar triangles at
/// once. 3 × 17 × `perPlane` triangles (30,600 by default).
inline SceneGeometry integerLattice(int perPlane = 600) {
    TriangleMesh m;
    Pcg32 rng(11, 0);
    auto below = [&](uint32_t n) { return int(rng.nextU32() % n); };
    for (int axis = 0; axis < 3; ++axis)
        for (int k = 0; k <= 16; ++k)
            for (int i = 0; i < perPlane; ++i) {
                int u = (axis + 1) % 3, v = (axis + 2) % 3;
                int a0 = below(16), b0 = below(16);
                int a1 = std::min(16, a0 + 1 + below(4)), b1 = std::min(16, b0 + 1 + below(4));
                Vec3f corner[4];
                for (int c = 0; c < 4; ++c) {
                    corner[c][axis] = float(k);
                    corner[c][u] = float(c & 1 ? a1 : a0);
                    corner[c][v] = float(c & 2 ? b1 : b0);
                }
                int skip = below(4);  // which corner of the rectangle the right triangle leaves out
                Vec3f tri[3];
                for (int c = 0, n = 0; c < 4; ++c)
                    if (c != skip) tri[n++] = corner[c];
                if (below(2)) std::swap(tri[1], tri[2]);  // both windings
                addTriangle(m, tri[0], tri[1], tri[2]);
            }
    m.name = "integer lattice";
    return withMesh(m);
}

/// A hairball: `count` long slivers crossing the cube [-1, 1]³, each from a random point of one face
/// to a random point of another, 1e-4 to 1e-3 wide at its middle: every ray passes many of them,
/// within a few ulps of their edges, where their planes are ill-conditioned.
inline SceneGeometry sliverHairball(int count = 60000) {
    TriangleMesh m;
    Pcg32 rng(13, 0);
    auto onFace = [&](int face) {
        Vec3f p(2.f * rng.nextFloat() - 1.f, 2.f * rng.nextFloat() - 1.f, 2.f * rng.nextFloat() - 1.f);
        p[face % 3] = face < 3 ? -1.f : 1.f;
        return p;
    };
    for (int i = 0; i < count; ++i) {
        int fa = int(rng.nextU32() % 6), fb = (fa + 1 + int(rng.nextU32() % 5)) % 6;
        Vec3f a = onFace(fa), b = onFace(fb);
        Vec3f side = glm::cross(b - a, Vec3f(rng.nextFloat() - 0.5f, rng.nextFloat() - 0.5f, rng.nextFloat() - 0.5f));
        float width = 1e-4f + 9e-4f * rng.nextFloat();
        float len = glm::length(side);
        Vec3f c = 0.5f * (a + b) + (len > 0.f ? width / len : 0.f) * side;
        addTriangle(m, a, b, c);
    }
    m.name = "sliver hairball";
    return withMesh(m);
}

/// `count` triangles of size 1e-6 scattered in the unit cube.
inline SceneGeometry tinyTriangles(int count = 2000) {
    TriangleMesh m;
    Pcg32 rng(5, 0);
    for (int i = 0; i < count; ++i) {
        Vec3f a(rng.nextFloat(), rng.nextFloat(), rng.nextFloat());
        addTriangle(m, a, a + Vec3f(1e-6f, 0, 0), a + Vec3f(0, 1e-6f, 1e-6f));
    }
    return withMesh(m);
}

/// A tessellated sphere with 30 analytic spheres in front of it (leaves mixing both kinds).
inline SceneGeometry spheresAndTriangles() {
    SceneGeometry g;
    g.meshes.push_back(makeUvSphereMesh(Vec3f(0), 1.f, 8, 16, 0));
    for (int i = 0; i < 30; ++i)
        g.spheres.push_back(Sphere{"s", Vec3f(float(i % 5) - 2.f, float(i / 5) * 0.4f - 1.f, 0.2f), 0.15f, 0});
    return g;
}

}  // namespace tessera::test
