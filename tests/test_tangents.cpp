// MikkTSpace tangent generation (scene/tangents.h): known answers on planar meshes, mirror seams,
// welding, and the angle weighting's independence of the triangulation.
#include <gtest/gtest.h>

#include <cmath>

#include "scene/tangents.h"

using namespace tessera;

namespace {

/// An n×n-quad grid on the plane z = 0 (normals +z) over [0, 1]², interior vertices jittered
/// (seeded) so the triangles differ in shape; uv = `uvOf`(x, y).
template <class UvFn>
TriangleMesh planarGrid(int n, UvFn uvOf) {
    TriangleMesh m;
    uint32_t state = 12345u;
    auto jitter = [&] {
        state = state * 1664525u + 1013904223u;
        return (float(state >> 8) / float(1u << 24) - 0.5f) * 0.3f / float(n);
    };
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            float x = float(i) / float(n), y = float(j) / float(n);
            if (i > 0 && i < n && j > 0 && j < n) x += jitter(), y += jitter();
            m.positions.emplace_back(x, y, 0.f);
            m.normals.emplace_back(0.f, 0.f, 1.f);
            m.texcoords[0].push_back(uvOf(x, y));
        }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
            m.triangles.emplace_back(a, b, d);
            m.triangles.emplace_back(a, d, c);
        }
    return m;
}

}  // namespace

// uv = S · R(θ) · (x, y) is affine in position, so ∂p/∂u is the same everywhere: the first column
// of (S R)⁻¹. glTF's v runs down the image and a normal map's +Y up it, so B = w · N × T must point
// along −∂p/∂v: w = −1 where the uv map preserves orientation in glTF's (u, v), +1 where mirrored.
TEST(MikkTangents, PlanarGridWithRotatedScaledUvsGivesTheAnalyticTangent) {
    for (bool mirrored : {false, true}) {
        const float theta = 0.7f, su = mirrored ? -2.f : 2.f, sv = 0.5f;
        const float c = std::cos(theta), s = std::sin(theta);
        TriangleMesh m = planarGrid(6, [&](float x, float y) { return Vec2f(su * (c * x - s * y), sv * (s * x + c * y)); });
        size_t vertices = m.positions.size();
        EXPECT_EQ(generateMikkTangents(m, 0), 0u);
        ASSERT_EQ(m.tangents.size(), vertices);
        // (S R)⁻¹ = Rᵀ S⁻¹: ∂p/∂u = Rᵀ (1/su, 0) = (c, −s)/su; ∂p/∂v = Rᵀ (0, 1/sv) = (s, c)/sv.
        Vec3f dpdu = glm::normalize(Vec3f(c, -s, 0.f) / su), dpdv = glm::normalize(Vec3f(s, c, 0.f) / sv);
        for (size_t v = 0; v < vertices; ++v) {
            const Vec4f& t = m.tangents[v];
            EXPECT_NEAR(t.x, dpdu.x, 1e-5f) << v;
            EXPECT_NEAR(t.y, dpdu.y, 1e-5f) << v;
            EXPECT_NEAR(t.z, 0.f, 1e-6f) << v;
            EXPECT_EQ(t.w, mirrored ? 1.f : -1.f) << v;
            Vec3f b = t.w * glm::cross(Vec3f(0, 0, 1), Vec3f(t));
            EXPECT_GT(glm::dot(b, -dpdv), 0.999f) << v;
        }
    }
}

// A mirror seam through shared vertices (uv = (x, y) left of x = 1, (2 − x, y) right of it: the
// seam vertices have the same uv on both sides): MikkTSpace gives the two sides separate
// tangents, so the seam vertices must be split.
TEST(MikkTangents, MirrorSeamSplitsTheSharedVertices) {
    TriangleMesh m = planarGrid(4, [](float x, float y) { return Vec2f(x, y); });
    for (Vec3f& p : m.positions) p.x *= 2.f;  // x in [0, 2]; seam at x = 1 (the column i = 2)
    for (size_t v = 0; v < m.positions.size(); ++v) {
        float x = m.positions[v].x;
        m.texcoords[0][v] = Vec2f(x <= 1.f ? x : 2.f - x, m.positions[v].y);
    }
    // Jitter moved interior seam vertices off x = 1; put the seam column back on it.
    for (int j = 0; j <= 4; ++j) {
        size_t v = size_t(j * 5 + 2);
        m.positions[v].x = 1.f;
        m.texcoords[0][v].x = 1.f;
    }
    size_t before = m.positions.size();
    EXPECT_EQ(generateMikkTangents(m, 0), 5u);  // the five seam vertices
    ASSERT_EQ(m.tangents.size(), before + 5);
    for (const glm::uvec3& t : m.triangles) {
        Vec3f centroid = (m.positions[t.x] + m.positions[t.y] + m.positions[t.z]) / 3.f;
        for (int k = 0; k < 3; ++k) {
            const Vec4f& tan = m.tangents[t[k]];
            if (centroid.x < 1.f) {
                EXPECT_NEAR(tan.x, 1.f, 1e-5f);
                EXPECT_EQ(tan.w, -1.f);
            } else {
                EXPECT_NEAR(tan.x, -1.f, 1e-5f);
                EXPECT_EQ(tan.w, 1.f);
            }
        }
    }
}

// Vertices with equal position, normal and uv are one vertex to MikkTSpace, whatever their index.
TEST(MikkTangents, IdenticalVerticesShareTheirTangent) {
    // Two triangles of a bent strip; vertex 1 and 4 are the same point given twice.
    TriangleMesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0.5f}, {1, 0, 0}};
    m.normals = std::vector<Vec3f>(5, glm::normalize(Vec3f(-0.1f, 0.f, 1.f)));
    m.texcoords[0] = {{0, 0}, {1, 0}, {0, 1}, {1, 1.5f}, {1, 0}};
    m.triangles = {{0, 1, 2}, {4, 3, 2}};
    generateMikkTangents(m, 0);
    EXPECT_EQ(m.tangents[1], m.tangents[4]);
    // Welded, the shared corner accumulates both faces: it differs from what either face alone gives.
    TriangleMesh alone = m;
    alone.triangles = {{0, 1, 2}};
    alone.tangents.clear();
    generateMikkTangents(alone, 0);
    EXPECT_GT(glm::length(Vec3f(m.tangents[1]) - Vec3f(alone.tangents[1])), 1e-3f);
}

// Angle weighting (Mikkelsen 2008, 4.2): splitting a face at a vertex into two coplanar faces with
// the same uv mapping leaves that vertex's tangent unchanged (a face-count weighting would not).
TEST(MikkTangents, SplittingAFaceAtAVertexKeepsItsTangent) {
    // A pyramid apex with three faces of different slope and uv stretch.
    TriangleMesh m;
    m.positions = {{0, 0, 1}, {1, 0, 0}, {-0.5f, 0.9f, 0.2f}, {-0.5f, -0.9f, 0.4f}};
    m.normals = {{0, 0, 1}, glm::normalize(Vec3f(1, 0, 1)), glm::normalize(Vec3f(-1, 1, 1)), glm::normalize(Vec3f(-1, -1, 1))};
    m.texcoords[0] = {{0.5f, 0.5f}, {1.3f, 0.4f}, {0.1f, 1.0f}, {0.2f, 0.0f}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}};
    TriangleMesh split = m;
    // Split face (0, 1, 2) by the apex–midpoint line of edge 1–2 (position and uv both midpoints,
    // so the sub-faces keep the face's plane and uv mapping).
    split.positions.push_back(0.5f * (m.positions[1] + m.positions[2]));
    split.normals.push_back(glm::normalize(m.normals[1] + m.normals[2]));
    split.texcoords[0].push_back(0.5f * (m.texcoords[0][1] + m.texcoords[0][2]));
    split.triangles = {{0, 1, 4}, {0, 4, 2}, {0, 2, 3}, {0, 3, 1}};
    generateMikkTangents(m, 0);
    generateMikkTangents(split, 0);
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(m.tangents[0][c], split.tangents[0][c], 1e-5f) << c;
    // And the weighting matters here: giving the split face double weight moves the tangent.
    TriangleMesh doubled = m;
    doubled.triangles.push_back({0, 1, 2});
    doubled.tangents.clear();
    generateMikkTangents(doubled, 0);
    EXPECT_GT(glm::length(Vec3f(doubled.tangents[0]) - Vec3f(m.tangents[0])), 1e-3f);
}

TEST(MikkTangents, FlatShadedPrimitivesAreUnweldedWithFaceNormals) {
    TriangleMesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    m.texcoords[0] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    m.triangles = {{0, 1, 2}, {0, 3, 1}};
    unweldWithFlatNormals(m);
    ASSERT_EQ(m.positions.size(), 6u);
    ASSERT_EQ(m.normals.size(), 6u);
    ASSERT_EQ(m.texcoords[0].size(), 6u);
    for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(m.normals[size_t(k)], Vec3f(0, 0, 1));
        EXPECT_EQ(m.normals[size_t(3 + k)], Vec3f(0, 1, 0));
    }
    EXPECT_EQ(m.texcoords[0][4], Vec2f(1, 1));
    generateMikkTangents(m, 0);
    for (size_t v = 0; v < 6; ++v) EXPECT_NEAR(glm::dot(Vec3f(m.tangents[v]), m.normals[v]), 0.f, 1e-6f);
}
