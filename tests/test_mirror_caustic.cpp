// The path no unbiased method samples: a point light's caustic seen in a mirror
// (scenes/sds-caustic/point-caustic-mirror.gltf: point light → glass sphere → floor → mirror →
// eye). pt never hits a point light, next-event estimation from the floor cannot pass the glass,
// light tracing cannot connect the floor to the lens through the mirror, and bdpt is made of these
// strategies; photon mapping merges at the floor. The independent estimate: the mirror is perfect
// (reflectance 1) and the floor Lambertian, so a pixel seeing the floor in the mirror shows the
// floor's radiance ρ E / π averaged over the pixel's footprint, and E is estimated by binning light
// sub-path vertices on the floor by footprint (a histogram of the flux, no camera paths and no
// kernel: unbiased for the footprint average). sppm and vcm must agree with it in the glass
// sphere's shadow, which the caustic fills (measured at 64 iterations of 2^16 photon paths, radius
// 0.04: +2.0% and +2.7% against an estimate of ±0.7%; seeds of sppm at 32 iterations spread ±5%),
// and every other integrator must fall far short there (pt and lt see nothing, ptnee and bdpt only
// the floor's light relayed by the mirror: 5% of it).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>

#include "core/thread_pool.h"
#include "integrators/path_vertex.h"
#include "render/renderer.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

constexpr int kW = 64, kH = 48;
const Vec3f kMirrorCentre(0.f, 4.f, 0.f);
const Vec3f kMirrorNormal = glm::normalize(Vec3f(0.f, -1.f, 1.f));
const Vec3f kMirrorUp = glm::normalize(Vec3f(0.f, 1.f, 1.f));
const Vec3f kSphereCentre(0.f, 0.9f, 0.f), kLight(-2.f, 2.4f, -2.9f);
constexpr float kSphereRadius = 0.5f, kFloorAlbedo = 0.8f;

Vec3f reflectAcrossMirror(const Vec3f& p) { return p - 2.f * glm::dot(p - kMirrorCentre, kMirrorNormal) * kMirrorNormal; }

/// Distance from `c` to the segment a–b.
float segmentDistance(const Vec3f& a, const Vec3f& b, const Vec3f& c) {
    Vec3f d = b - a;
    float t = std::clamp(glm::dot(c - a, d) / glm::dot(d, d), 0.f, 1.f);
    return glm::length(a + t * d - c);
}

/// Where the camera ray through `raster` meets the floor after the mirror; false when it misses
/// the mirror or the floor, or passes near the glass sphere.
bool floorPointThroughMirror(const Camera& camera, Vec2f raster, Vec3f& floorPoint) {
    Ray ray = camera.generateRay(raster, Vec2f(0.5f));
    float tm = glm::dot(kMirrorCentre - ray.o, kMirrorNormal) / glm::dot(ray.d, kMirrorNormal);
    if (!(tm > 0.f)) return false;
    Vec3f m = ray.o + tm * ray.d;
    if (std::abs(m.x) > 2.4f || std::abs(glm::dot(m - kMirrorCentre, kMirrorUp)) > 2.2f) return false;
    Vec3f d = ray.d - 2.f * glm::dot(ray.d, kMirrorNormal) * kMirrorNormal;
    if (!(d.y < 0.f)) return false;
    floorPoint = m + (-m.y / d.y) * d;
    floorPoint.y = 0.f;
    if (std::abs(floorPoint.x) > 3.9f || std::abs(floorPoint.z) > 3.9f) return false;
    return segmentDistance(m, floorPoint, kSphereCentre) > kSphereRadius + 0.03f;
}

struct Footprints {
    std::vector<double> area;  ///< floor area seen by each pixel through the mirror; 0: pixel not judged
    std::vector<Vec3f> centre;
};

Footprints footprints(const Camera& camera) {
    Footprints f{std::vector<double>(size_t(kW * kH), 0.0), std::vector<Vec3f>(size_t(kW * kH), Vec3f(0.f))};
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            std::array<Vec3f, 4> c;
            const Vec2f corners[4] = {{0.f, 0.f}, {1.f, 0.f}, {1.f, 1.f}, {0.f, 1.f}};
            bool ok = floorPointThroughMirror(camera, Vec2f(float(x) + 0.5f, float(y) + 0.5f), f.centre[size_t(y * kW + x)]);
            for (int k = 0; k < 4 && ok; ++k) ok = floorPointThroughMirror(camera, Vec2f(float(x), float(y)) + corners[k], c[size_t(k)]);
            if (!ok) continue;
            // The map from raster to floor is projective: the footprint is the quadrilateral.
            double area = 0.0;
            for (int k = 0; k < 4; ++k) {
                const Vec3f &a = c[size_t(k)], &b = c[size_t((k + 1) % 4)];
                area += double(a.x) * b.z - double(b.x) * a.z;
            }
            f.area[size_t(y * kW + x)] = std::abs(area) / 2.0;
        }
    return f;
}

/// The floor's radiance ρ E / π averaged over each pixel's footprint, from `paths` light
/// sub-paths (luminance), in `batches` independent batches (for the standard error).
std::vector<std::vector<double>> histogramEstimate(const RenderContext& ctx, const Footprints& fp, uint64_t paths, int batches) {
    std::vector<std::vector<double>> result(size_t(batches), std::vector<double>(fp.area.size(), 0.0));
    ThreadPool pool(2);
    const uint64_t perBatch = paths / uint64_t(batches);
    pool.parallelFor(size_t(batches), [&](size_t b) {
        std::vector<PathVertex> path;
        std::vector<double>& sum = result[b];
        for (uint64_t k = 0; k < perBatch; ++k) {
            Sampler sampler(Vec2i(int(k), -7 - int(b)), 0, 12345, SamplerKind::Independent);
            traceLightSubpath(ctx, sampler, -1, path);
            for (size_t j = 1; j < path.size(); ++j) {
                const PathVertex& v = path[j];
                if (v.type != VertexType::Surface || std::abs(v.p.y) > 1e-3f || v.ng.y < 0.99f) continue;
                CameraSample cs;
                if (!ctx.camera.sampleIncoming(reflectAcrossMirror(v.p), Vec2f(0.5f), cs)) continue;
                int x = int(cs.raster.x), y = int(cs.raster.y);
                if (x < 0 || y < 0 || x >= kW || y >= kH || fp.area[size_t(y * kW + x)] <= 0.0) continue;
                double flux = luminance(v.beta);
                sum[size_t(y * kW + x)] += kFloorAlbedo / kPi * flux / fp.area[size_t(y * kW + x)];
            }
        }
        for (double& s : sum) s /= double(perBatch);
    });
    return result;
}

double regionSum(const std::vector<double>& image, const std::vector<bool>& region) {
    double s = 0.0;
    for (size_t i = 0; i < image.size(); ++i)
        if (region[i]) s += image[i];
    return s;
}

std::vector<double> renderMirrorLuminance(const Scene& scene, const Integrator& integrator, int spp, uint64_t seed) {
    auto accel = createAccel("embree", scene.geometry);
    test::TestRender r = test::renderScene(scene, *accel, integrator, kW, kH, RenderOptions{.spp = spp, .threads = 2, .seed = seed});
    EXPECT_EQ(r.stats.nonFiniteDropped, 0u);
    return test::filmLuminance(r.film);
}

}  // namespace

TEST(MirrorCaustic, OnlyPhotonMappingSeesAPointLightsCausticInAMirror) {
    Scene scene = test::loadSourceScene("scenes/sds-caustic/point-caustic-mirror.gltf");
    auto accel = createAccel("embree", scene.geometry);
    Camera camera(*scene.camera, kW, kH);
    RenderContext ctx{scene, *accel, camera, -1};
    Footprints fp = footprints(camera);

    const int batches = 8;
    std::vector<std::vector<double>> est = histogramEstimate(ctx, fp, 4000000, batches);
    std::vector<double> mean(fp.area.size(), 0.0);
    for (const auto& b : est)
        for (size_t i = 0; i < mean.size(); ++i) mean[i] += b[i] / batches;
    // The caustic fills the glass sphere's shadow on the floor (a ball lens aberrates too much to
    // focus a spot): the region is the judged footprints whose centre is in the shadow by a margin
    // of 0.1 (at the sphere), where there is no direct light to blur in.
    std::vector<bool> region(mean.size());
    size_t nRegion = 0;
    for (size_t i = 0; i < mean.size(); ++i) {
        region[i] = fp.area[i] > 0.0 && segmentDistance(fp.centre[i], kLight, kSphereCentre) < kSphereRadius - 0.1f;
        nRegion += region[i];
    }
    ASSERT_GT(nRegion, 30u) << "the shadow is not in the mirror";
    // The estimate's region sum and its standard error over the batches.
    const double expected = regionSum(mean, region);
    double var = 0.0;
    for (const auto& b : est) var += (regionSum(b, region) - expected) * (regionSum(b, region) - expected) / (batches - 1);
    const double se = std::sqrt(var / batches);
    std::cout << nRegion << " pixels in the shadow; histogram estimate " << expected << " ± " << se << "\n";
    ASSERT_LT(se, 0.01 * expected);

    // A radius of 0.04 (the default here would be 0.2, the shadow's width is ~1) and 2^16 photon
    // paths per iteration keep the blur across the shadow's edge small.
    RenderSettings settings;
    settings.photonRadius = 0.04f;
    settings.photonPaths = 65536;
    for (const char* name : {"sppm", "vcm"}) {
        settings.integrator = name;
        double got = regionSum(renderMirrorLuminance(scene, *createIntegrator(settings), 64, 3), region);
        std::cout << name << ": " << got << " (" << (got / expected - 1.0) * 100.0 << "%)\n";
        EXPECT_NEAR(got, expected, 0.08 * expected) << name;
    }
    for (const char* name : {"pt", "ptnee", "lt", "bdpt"}) {
        double got = regionSum(renderMirrorLuminance(scene, *createIntegrator(name), 16, 3), region);
        std::cout << name << ": " << got << " (" << (got / expected - 1.0) * 100.0 << "%)\n";
        EXPECT_LT(got, 0.1 * expected) << name << " cannot sample the caustic: it must not be there";
    }
}
