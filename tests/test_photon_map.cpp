// The photon structures (accel/photon_map.h) against brute force: every point within the radius,
// each once, on point sets shaped like photon maps (points on planes, clusters, duplicates) and on
// the awkward ones (points exactly at the radius, on split planes, non-finite), and the same
// layout and visiting order for any thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "accel/photon_map.h"
#include "cli_run.h"
#include "core/rng.h"
#include "core/thread_pool.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

std::vector<uint32_t> bruteWithin(std::span<const Vec3f> points, const Vec3f& x, float radius) {
    std::vector<uint32_t> found;
    if (!isFinite(x)) return found;
    for (size_t i = 0; i < points.size(); ++i) {
        Vec3f d = points[i] - x;
        if (isFinite(points[i]) && glm::dot(d, d) <= radius * radius) found.push_back(uint32_t(i));
    }
    return found;
}

template <class Structure>
std::vector<uint32_t> within(const Structure& s, const Vec3f& x, float radius) {
    std::vector<uint32_t> found;
    s.forEachWithin(x, radius, [&](uint32_t i) { found.push_back(i); });
    return found;
}

/// Photons as light paths leave them: most on a few planes (floor, walls), some in a cluster (a
/// caustic), a few scattered, some exact duplicates.
std::vector<Vec3f> photonLikePoints(size_t n, uint64_t seed) {
    Pcg32 rng(seed, 3);
    std::vector<Vec3f> p;
    for (size_t i = 0; i < n; ++i) {
        float u = rng.nextFloat(), v = rng.nextFloat(), w = rng.nextFloat();
        switch (i % 5) {
        case 0: p.push_back({u, 0.f, v}); break;                                  // floor y = 0
        case 1: p.push_back({0.f, u, v}); break;                                  // wall x = 0
        case 2: p.push_back({0.5f + 0.02f * u, 0.f, 0.5f + 0.02f * v}); break;    // caustic cluster
        case 3: p.push_back({u, v, w}); break;                                    // volume-like scatter
        default: p.push_back(p.empty() ? Vec3f(0.25f) : p[i / 2]); break;         // duplicates
        }
    }
    return p;
}

/// Checks both structures against brute force on `queries` random queries (plus every point used as
/// a query, which puts a point at distance 0 and its duplicates at the same place).
void expectBothMatchBrute(const std::vector<Vec3f>& points, float radius, size_t queries, uint64_t seed, size_t tableSize = 0) {
    PhotonKdTree kd;
    kd.build(points);
    PhotonHashGrid grid;
    grid.build(points, radius, nullptr, tableSize);
    Pcg32 rng(seed, 7);
    std::vector<Vec3f> xs;
    for (size_t q = 0; q < queries; ++q) xs.push_back({1.2f * rng.nextFloat() - 0.1f, 1.2f * rng.nextFloat() - 0.1f, 1.2f * rng.nextFloat() - 0.1f});
    for (size_t i = 0; i < points.size(); i += 7) xs.push_back(points[i]);
    size_t total = 0;
    for (const Vec3f& x : xs) {
        for (float r : {radius, 0.5f * radius, 0.f}) {
            std::vector<uint32_t> expected = bruteWithin(points, x, r), k = within(kd, x, r), g = within(grid, x, r);
            total += expected.size();
            std::sort(k.begin(), k.end());
            std::sort(g.begin(), g.end());
            ASSERT_EQ(k, expected) << "k-d tree, query (" << x.x << ", " << x.y << ", " << x.z << "), r = " << r;
            ASSERT_EQ(g, expected) << "hash grid, query (" << x.x << ", " << x.y << ", " << x.z << "), r = " << r;
        }
    }
    EXPECT_GT(total, xs.size()) << "the queries found too few points to test anything";
}

}  // namespace

TEST(PhotonMap, BothStructuresFindExactlyThePointsWithinTheRadius) {
    expectBothMatchBrute(photonLikePoints(20000, 1), 0.02f, 2000, 2);
    expectBothMatchBrute(photonLikePoints(3000, 3), 0.1f, 1000, 4);
}

TEST(PhotonMap, HashCollisionsNeitherLoseNorRepeatPoints) {
    // One bucket for every cell: all eight cells of a query collide, and a bucket visited twice
    // would report its points twice (the sorted lists would then differ from brute force).
    expectBothMatchBrute(photonLikePoints(2000, 5), 0.05f, 300, 6, /*tableSize=*/1);
    expectBothMatchBrute(photonLikePoints(2000, 7), 0.05f, 300, 8, /*tableSize=*/3);
}

TEST(PhotonMap, PointsExactlyAtTheRadiusAndOnSplitPlanesAreFound) {
    // An integer lattice: every coordinate is a split plane of the k-d tree and a cell border of the
    // grid, and with radius 1 each lattice query has its 6 neighbours at exactly the radius.
    std::vector<Vec3f> points;
    for (int z = 0; z < 12; ++z)
        for (int y = 0; y < 12; ++y)
            for (int x = 0; x < 12; ++x) points.push_back(Vec3f(float(x), float(y), float(z)));
    PhotonKdTree kd;
    kd.build(points);
    PhotonHashGrid grid;
    grid.build(points, 1.f);
    for (const Vec3f& x : points) {
        std::vector<uint32_t> expected = bruteWithin(points, x, 1.f), k = within(kd, x, 1.f), g = within(grid, x, 1.f);
        std::sort(k.begin(), k.end());
        std::sort(g.begin(), g.end());
        ASSERT_EQ(k, expected);
        ASSERT_EQ(g, expected);
    }
    EXPECT_EQ(within(kd, Vec3f(5.f), 1.f).size(), 7u);  // itself and its six neighbours
}

TEST(PhotonMap, DegenerateSetsAndQueries) {
    const float nan = std::nanf(""), inf = INFINITY;
    // Empty, one point, all points equal, non-finite points (left out), non-finite queries.
    for (const std::vector<Vec3f>& points : {std::vector<Vec3f>{}, std::vector<Vec3f>{Vec3f(1.f)}, std::vector<Vec3f>(500, Vec3f(0.3f)),
                                              std::vector<Vec3f>{Vec3f(0.f), Vec3f(nan, 0.f, 0.f), Vec3f(0.01f), Vec3f(inf), Vec3f(0.02f)}}) {
        PhotonKdTree kd;
        kd.build(points);
        PhotonHashGrid grid;
        grid.build(points, 0.05f);
        for (const Vec3f& x : {Vec3f(0.f), Vec3f(0.3f), Vec3f(1.f), Vec3f(nan), Vec3f(-inf, 0.f, 0.f), Vec3f(1e30f)}) {
            std::vector<uint32_t> expected = bruteWithin(points, x, 0.05f), k = within(kd, x, 0.05f), g = within(grid, x, 0.05f);
            std::sort(k.begin(), k.end());
            std::sort(g.begin(), g.end());
            EXPECT_EQ(k, expected) << points.size() << " points";
            EXPECT_EQ(g, expected) << points.size() << " points";
        }
    }
    // A radius above the grid's build radius is refused (finds nothing) rather than answered wrongly.
    PhotonHashGrid grid;
    grid.build(std::vector<Vec3f>{Vec3f(0.f)}, 0.1f);
    EXPECT_TRUE(within(grid, Vec3f(0.f), 0.2f).empty());
}

TEST(PhotonMap, LayoutAndVisitingOrderDoNotDependOnTheThreadCount) {
    std::vector<Vec3f> points = photonLikePoints(50000, 9);
    PhotonKdTree serial, parallel;
    serial.build(points, nullptr);
    ThreadPool pool(4);
    parallel.build(points, &pool);
    PhotonHashGrid gridSerial, gridParallel;
    gridSerial.build(points, 0.01f, nullptr);
    gridParallel.build(points, 0.01f, &pool);
    Pcg32 rng(10, 1);
    for (int q = 0; q < 500; ++q) {
        Vec3f x(rng.nextFloat(), rng.nextFloat() * 0.1f, rng.nextFloat());
        // Unsorted: the order a merging integrator would sum in.
        ASSERT_EQ(within(serial, x, 0.01f), within(parallel, x, 0.01f));
        ASSERT_EQ(within(gridSerial, x, 0.01f), within(gridParallel, x, 0.01f));
    }
}

TEST(PhotonMap, BenchCommandMeasuresBothStructuresOnTheSamePhotons) {
    // `bench-photons` exits 1 when the two structures find different numbers of photons, 2 on a
    // scene it cannot read.
    auto dir = tessera::test::tempDir("bench-photons");
    const std::string box = tessera::test::sourcePath("scenes/cornell-box/cornell-box.gltf");
    tessera::test::CliRun r = tessera::test::runTessera(dir, "bench-photons '" + box + "' --photons 20000 --queries 2000 --repeat 1 --radius-factor 0.01 --json");
    ASSERT_EQ(r.code, 0) << r.err;
    nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_GT(j["photons"].get<size_t>(), 10000u);
    EXPECT_GT(j["photonsPerQuery"].get<double>(), 1.0);
    EXPECT_NEAR(j["kdtree"]["bytesPerPhoton"].get<double>(), 17.0, 0.5);
    EXPECT_NEAR(j["hashgrid"]["bytesPerPhoton"].get<double>(), 20.0, 0.5);
    EXPECT_EQ(tessera::test::runTessera(dir, "bench-photons missing.gltf").code, 2);
}
