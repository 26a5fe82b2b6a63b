// χ² goodness-of-fit of every sampling routine against its own density (pbrt / Nori style):
// BSDF sampling at several incident angles, light sampling from a point, light emission directions.
// Per sample: weight == f·|cos|/pdf and the reported densities equal pdf(). Levels are Šidák-corrected
// over all χ² tests in this file.
#include <gtest/gtest.h>

#include <functional>

#include "accel/accel.h"
#include "core/frame.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "materials/surface_bsdf.h"
#include "scene/scene.h"
#include "chi2_harness.h"
#include "test_helpers.h"

using namespace tessera;
using namespace tessera::test;

namespace {

constexpr int kChi2Tests = 3 * 3 + 3 + 2;  // BSDFs × angles, light-sampling points, emission
constexpr double kAlpha = 0.01;

double sidakLevel() { return 1.0 - std::pow(1.0 - kAlpha, 1.0 / kChi2Tests); }

Material makeMaterial(MaterialType type, float alpha) {
    Material m;
    m.bsdf.type = type;
    m.bsdf.baseColor = Rgb(0.9f, 0.7f, 0.5f);
    m.bsdf.alpha = alpha;
    return m;
}

}  // namespace

TEST(SamplingChi2, BsdfSamplesFollowTheirPdfAndWeightsEqualEvalCosOverPdf) {
    const int n = 200000;
    std::vector<Material> materials = {makeMaterial(MaterialType::Diffuse, 0.f), makeMaterial(MaterialType::RoughConductor, 0.3f),
                                       makeMaterial(MaterialType::RoughConductor, 0.7f)};
    const Vec3f nz(0.f, 0.f, 1.f);
    for (const Material& m : materials) {
        for (float thetaDeg : {10.f, 45.f, 80.f}) {
            float th = thetaDeg * kPi / 180.f;
            Vec3f wo(std::sin(th), 0.f, std::cos(th));
            SurfaceBsdf bsdf(m.bsdf, nz, nz);
            std::vector<int> counts(size_t(kThetaBins * kPhiBins + 1), 0);
            Pcg32 rng(uint64_t(thetaDeg * 10) + uint64_t(m.bsdf.alpha * 1000), 3);
            int badWeight = 0, badPdf = 0;
            for (int i = 0; i < n; ++i) {
                SurfaceBsdfSample bs;
                float uLobe = rng.nextFloat();
                Vec2f u = rng.next2D();
                if (!bsdf.sample(wo, uLobe, u, TransportMode::Radiance, bs)) {
                    ++counts.back();
                    continue;
                }
                ++counts[size_t(cellOf(bs.wiWorld))];
                // Per sample: weight = f |cos| / pdf and pdfFwd = pdf(wo, wi).
                float pdf = bsdf.pdfFwdW(wo, bs.wiWorld);
                Rgb expectW = bsdf.eval(wo, bs.wiWorld, TransportMode::Radiance) * std::abs(bs.wiWorld.z) / pdf;
                if (std::abs(pdf - bs.pdfFwdW) > 1e-3f * pdf) ++badPdf;
                if (glm::length(expectW - bs.weight) > 1e-3f * glm::length(expectW) + 1e-6f) ++badWeight;
            }
            std::string what = "material " + std::to_string(int(m.bsdf.type)) + " alpha " + std::to_string(m.bsdf.alpha) + " theta " +
                               std::to_string(thetaDeg);
            EXPECT_LE(badPdf, n / 10000) << what;
            EXPECT_LE(badWeight, n / 10000) << what;
            std::vector<double> prob = integrateCells([&](const Vec3f& wi) { return double(bsdf.pdfFwdW(wo, wi)); }, 16);
            double p = chi2Test(counts, prob, n, what);
            EXPECT_GT(p, sidakLevel()) << what;
        }
    }
}

TEST(SamplingChi2, ImportanceTransportWeightCarriesTheShadingNormalCorrection) {
    // With a shading normal tilted away from the geometric one, importance-mode sampling must
    // weight by the adjoint BSDF f*·|cos_s|/pdf = f·|wo·ns||wi·ng|/(|wo·ng| pdf) (Veach 1997, eq. 5.19)
    // and radiance mode by f·|wi·ns|/pdf; the two differ exactly by the correction factor.
    Material m = makeMaterial(MaterialType::Diffuse, 0.f);
    Vec3f ng(0.f, 0.f, 1.f), ns = glm::normalize(Vec3f(0.3f, 0.1f, 1.f));
    SurfaceBsdf bsdf(m.bsdf, ns, ng);
    Pcg32 rng(5, 5);
    for (int i = 0; i < 1000; ++i) {
        Vec3f wo = sampleCosineHemisphere(rng.next2D());
        SurfaceBsdfSample r, imp;
        float uLobe = rng.nextFloat();
        Vec2f u = rng.next2D();
        bool okR = bsdf.sample(wo, uLobe, u, TransportMode::Radiance, r);
        bool okI = bsdf.sample(wo, uLobe, u, TransportMode::Importance, imp);
        ASSERT_EQ(okR, okI);
        if (!okR) continue;
        float corr = std::abs(glm::dot(wo, ns)) * std::abs(glm::dot(r.wiWorld, ng)) /
                     (std::abs(glm::dot(wo, ng)) * std::abs(glm::dot(r.wiWorld, ns)));
        EXPECT_NEAR(imp.weight.r, r.weight.r * corr, 1e-4f * r.weight.r * corr + 1e-6f);
        Rgb fImp = bsdf.eval(wo, r.wiWorld, TransportMode::Importance);
        EXPECT_NEAR(fImp.g * std::abs(glm::dot(r.wiWorld, ns)) / r.pdfFwdW, imp.weight.g, 1e-4f * imp.weight.g + 1e-6f);
    }
}

TEST(SamplingChi2, LightSamplingFromAPointFollowsPdfW) {
    // A triangle light and a sphere light on opposite sides of the reference points, so that every
    // direction meets at most one light: the density of a direction is that light's pdfW.
    Scene scene;
    Material emit;
    emit.emission = Rgb(1.f, 2.f, 3.f);
    scene.materials.push_back(emit);
    TriangleMesh tri;
    // Large lights: the midpoint rule's error sits on the cells a light's outline crosses.
    tri.positions = {Vec3f(-2.f, -2.f, 1.0f), Vec3f(2.5f, -1.f, 0.8f), Vec3f(0.f, 2.5f, 1.5f)};
    tri.triangles = {glm::uvec3(0, 1, 2)};
    scene.geometry.meshes.push_back(tri);
    scene.geometry.spheres.push_back(Sphere{"s", Vec3f(0.3f, 0.2f, -2.2f), 1.2f, 0});
    scene.pointLights.push_back(PointLightDesc{Vec3f(5.f, 5.f, 5.f), Rgb(1.f)});  // picked but delta: its own cell
    scene.finalize();
    auto accel = createAccel("brute", scene.geometry);
    const LightSet& lights = scene.lights();
    const int n = 200000;
    for (Vec3f ref : {Vec3f(0.f), Vec3f(0.2f, -0.3f, 0.1f), Vec3f(-0.4f, 0.4f, -0.6f)}) {
        std::vector<int> counts(size_t(kThetaBins * kPhiBins + 1), 0);
        Pcg32 rng(11, uint64_t(ref.x * 100 + 7));
        double pointPmf = 0.0;
        int pointCount = 0;
        for (int i = 0; i < n; ++i) {
            LightSample ls;
            float uPick = rng.nextFloat();
            Vec2f u = rng.next2D();
            if (!lights.sample(ref, uPick, u, ls)) {
                ++counts.back();
                continue;
            }
            if (ls.isDelta) {
                ++pointCount;
                pointPmf = ls.pdfW;
                continue;
            }
            ++counts[size_t(cellOf(glm::normalize(ls.p - ref)))];
            float pdf = lights.pdfW(ls.index, ref, ls.p, ls.n);
            EXPECT_NEAR(pdf, ls.pdfW, 1e-3f * pdf);
        }
        // The point light's share is a binomial count with probability pmf.
        double e = pointPmf * n;
        EXPECT_LT(std::abs(pointCount - e), 5.0 * std::sqrt(e * (1.0 - pointPmf)) + 1.0);
        std::vector<double> prob = integrateCells([&](const Vec3f& w) {
            Hit hit;
            Ray ray{ref, w, 0.f, kInfinity};
            if (!accel->intersect(ray, hit)) return 0.0;
            SurfaceInteraction si = scene.interaction(ray, hit);
            return double(lights.pdfW(si.lightIndex, ref, si.p, si.ng));
        }, 40);
        // pdfW includes the pick probability, so the cells hold 1 − pmf(point) in all; the point
        // light's samples (checked above) join the remainder cell, whose probability is pmf(point).
        counts.back() += pointCount;
        double pc = chi2Test(counts, prob, n, "light sampling");
        EXPECT_GT(pc, sidakLevel()) << "reference point " << ref.x << "," << ref.y << "," << ref.z;
    }
}

TEST(SamplingChi2, LightEmissionDirectionsFollowPdfDirW) {
    for (bool twoSided : {false, true}) {
        Scene scene;
        Material emit;
        emit.emission = Rgb(1.f);
        emit.doubleSided = twoSided;
        scene.materials.push_back(emit);
        TriangleMesh tri;
        tri.positions = {Vec3f(-1.f, -1.f, 0.f), Vec3f(1.f, -1.f, 0.f), Vec3f(0.f, 1.f, 0.f)};  // normal +z
        tri.triangles = {glm::uvec3(0, 1, 2)};
        scene.geometry.meshes.push_back(tri);
        scene.finalize();
        const LightSet& lights = scene.lights();
        const int n = 200000;
        std::vector<int> counts(size_t(kThetaBins * kPhiBins + 1), 0);
        Pcg32 rng(twoSided ? 2 : 1, 9);
        for (int i = 0; i < n; ++i) {
            LightEmission le;
            float uPick = rng.nextFloat();
            Vec2f uPos = rng.next2D(), uDir = rng.next2D();
            if (!lights.sampleEmission(uPick, uPos, uDir, le)) {
                ++counts.back();
                continue;
            }
            ++counts[size_t(cellOf(le.dir))];
            float pdfPosA, pdfDirW;
            lights.pdfEmission(le.index, le.n, le.dir, pdfPosA, pdfDirW);
            EXPECT_NEAR(pdfDirW, le.pdfDirW, 1e-4f * pdfDirW);
            EXPECT_NEAR(pdfPosA, 1.f / 2.f, 1e-5f);  // area of the triangle: 2
        }
        std::vector<double> prob = integrateCells([&](const Vec3f& w) {
            float pdfPosA, pdfDirW;
            lights.pdfEmission(0, Vec3f(0.f, 0.f, 1.f), w, pdfPosA, pdfDirW);
            return double(pdfDirW);
        });
        double p = chi2Test(counts, prob, n, twoSided ? "two-sided emission" : "one-sided emission");
        EXPECT_GT(p, sidakLevel());
    }
}

// Delta BSDFs have no density to histogram: their "χ²" is the discrete lobe choice. The dielectric
// must reflect with probability F (Fresnel) and refract otherwise, along Snell's direction; the
// radiance weight of a refraction carries (η_i/η_t)², the importance weight does not (Veach 1997,
// §5.2; the pbrt bug of applying it to both). The mirror reflects exactly.
TEST(SamplingChi2, DeltaBsdfsPickLobesByFresnelAndScaleOnlyRadiance) {
    Material glass = makeMaterial(MaterialType::Dielectric, 0.f);
    glass.bsdf.baseColor = Rgb(1.f);
    glass.bsdf.ior = 1.5f;
    Material mirror = makeMaterial(MaterialType::Mirror, 0.f);
    const Vec3f nz(0.f, 0.f, 1.f);
    const int n = 100000;
    for (float thetaDeg : {10.f, 60.f, 85.f}) {
        for (float side : {1.f, -1.f}) {  // arriving from outside, and from inside the glass
            float th = thetaDeg * kPi / 180.f;
            Vec3f wo(std::sin(th), 0.f, side * std::cos(th));
            SurfaceBsdf bsdf(glass.bsdf, nz, nz);
            float F = fresnelDielectric(wo.z, glass.bsdf.ior);
            float etaT = side > 0.f ? glass.bsdf.ior : 1.f, etaI = side > 0.f ? 1.f : glass.bsdf.ior;
            Pcg32 rng(uint64_t(thetaDeg), side > 0.f ? 1u : 2u);
            int reflected = 0;
            for (int i = 0; i < n; ++i) {
                float uLobe = rng.nextFloat();
                Vec2f u = rng.next2D();
                SurfaceBsdfSample r, imp;
                ASSERT_TRUE(bsdf.sample(wo, uLobe, u, TransportMode::Radiance, r));
                ASSERT_TRUE(bsdf.sample(wo, uLobe, u, TransportMode::Importance, imp));
                EXPECT_TRUE(r.isDelta);
                if (r.wiWorld.z * wo.z > 0.f) {
                    ++reflected;
                    EXPECT_NEAR(r.wiWorld.x, -wo.x, 1e-5f);
                    EXPECT_NEAR(r.wiWorld.z, wo.z, 1e-5f);
                    EXPECT_NEAR(r.weight.r, 1.f, 1e-5f);
                } else {
                    // Snell: η_i sin θ_i = η_t sin θ_t, and the tangential direction flips.
                    EXPECT_NEAR(etaI * wo.x, -etaT * r.wiWorld.x, 1e-4f);
                    EXPECT_NEAR(r.weight.r, (etaI / etaT) * (etaI / etaT), 1e-4f);
                    EXPECT_NEAR(imp.weight.r, 1.f, 1e-5f);
                }
            }
            double e = double(F) * n, sd = std::sqrt(double(n) * F * (1.0 - F));
            EXPECT_LT(std::abs(reflected - e), 5.0 * sd + 1.0) << "theta " << thetaDeg << " side " << side << " F " << F;
        }
        SurfaceBsdf m(mirror.bsdf, nz, nz);
        Vec3f wo(std::sin(thetaDeg * kPi / 180.f), 0.f, std::cos(thetaDeg * kPi / 180.f));
        SurfaceBsdfSample r;
        ASSERT_TRUE(m.sample(wo, 0.3f, Vec2f(0.2f, 0.7f), TransportMode::Radiance, r));
        EXPECT_NEAR(glm::length(r.wiWorld - Vec3f(-wo.x, -wo.y, wo.z)), 0.f, 1e-6f);
        EXPECT_EQ(m.pdfFwdW(wo, r.wiWorld), 0.f);  // delta: no density off the sampling routine
    }
}
