// The glTF 2.0 metallic-roughness BSDF (materials/gltf_pbr.h): sampling against its own density
// (χ², Šidák-corrected over this file), sample weights against eval/pdf, reciprocity (with the η²
// rule of refraction), energy (white furnace of the BSDF, the loss printed per roughness), the exact
// special cases (Lambert, mirror, smooth glass) and finite values on degenerate inputs.
#include <gtest/gtest.h>

#include <cstdio>

#include "chi2_harness.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "materials/surface_bsdf.h"
#include "test_helpers.h"

using namespace tessera;
using namespace tessera::test;

namespace {

struct Point {
    const char* name;
    Rgb base;
    float metallic, roughness, transmission = 0.f, specular = 1.f;
    bool thin = true;
    float ior = 1.5f;
    Rgb specularColor{1.f};
};

BsdfParams makeParams(const Point& pt) {
    BsdfParams p;
    p.baseColor = pt.base;
    p.metallic = pt.metallic;
    p.alpha = pt.roughness * pt.roughness;
    p.transmission = pt.transmission;
    p.specular = pt.specular;
    p.specularColor = pt.specularColor;
    p.thinWalled = pt.thin;
    p.ior = pt.ior;
    finalizeBsdfParams(p);
    return p;
}

/// The glTF model itself (MaterialType::Pbr), also where finalizeBsdfParams would pick a special case.
BsdfParams forcePbr(BsdfParams p) {
    p.type = MaterialType::Pbr;
    return p;
}

Vec3f direction(float thetaDeg, float phiDeg = 0.f) {
    float th = thetaDeg * kPi / 180.f, ph = phiDeg * kPi / 180.f;
    return {std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
}

const Point kChi2Points[] = {
    {"rough plastic", Rgb(0.8f, 0.3f, 0.2f), 0.f, 0.5f},
    {"half metal", Rgb(0.9f, 0.6f, 0.3f), 0.5f, 0.3f},
    {"rough glass volume", Rgb(1.f), 0.f, 0.4f, 1.f, 1.f, false},
    {"rough thin transmission", Rgb(0.9f, 0.9f, 0.7f), 0.f, 0.3f, 0.7f, 1.f, true},
    {"tinted specular, dense volume", Rgb(0.6f, 0.8f, 0.9f), 0.2f, 0.6f, 0.3f, 0.5f, false, 1.8f, Rgb(1.f, 0.5f, 0.2f)},
    {"smooth plastic (delta coat)", Rgb(0.5f, 0.7f, 0.3f), 0.f, 0.f},
    {"black rough metal", Rgb(0.f), 1.f, 0.4f},
};
// Outside at 10°, 45°, 80°; transmissive volumes also from inside (135°: beyond the critical angle
// for part of the microfacets).
const float kAngles[] = {10.f, 45.f, 80.f, 135.f};
constexpr int kChi2Tests = 7 * 4;
// The histogram's pole lies along the tangent y: lobes around the normal (narrow refraction lobes
// at near-normal incidence) fall where the (cos θ, φ) cells are regular, not on the pole where the
// midpoint rule cannot resolve them. A rotation (cyclic permutation) and its inverse.
Vec3f toBinFrame(const Vec3f& w) { return {w.z, w.x, w.y}; }
Vec3f fromBinFrame(const Vec3f& b) { return {b.y, b.z, b.x}; }
constexpr double kAlpha = 0.01;
double sidakLevel() { return 1.0 - std::pow(1.0 - kAlpha, 1.0 / kChi2Tests); }

}  // namespace

// Samples follow pdfFwdW: delta samples (smooth lobes) join the remainder cell, whose expected
// probability is 1 − ∫pdf. Per sample: weight = f·|cos|/pdf and pdfFwdW = pdf(wo, wi).
TEST(GltfBsdf, SamplesFollowTheMixtureDensityAndWeightsMatchEval) {
    const int n = 200000;
    const Vec3f nz(0.f, 0.f, 1.f);
    for (const Point& pt : kChi2Points) {
        BsdfParams p = makeParams(pt);
        SurfaceBsdf bsdf(p, nz, nz);
        for (float theta : kAngles) {
            Vec3f wo = direction(theta, 20.f);
            std::vector<int> counts(size_t(kThetaBins * kPhiBins + 1), 0);
            Pcg32 rng(uint64_t(theta * 7.f) + 1, uint64_t(&pt - kChi2Points) + 11);
            int badWeight = 0, badPdf = 0, deltaCount = 0;
            for (int i = 0; i < n; ++i) {
                SurfaceBsdfSample bs;
                float uLobe = rng.nextFloat();
                Vec2f u = rng.next2D();
                if (!bsdf.sample(wo, uLobe, u, TransportMode::Radiance, bs)) {
                    ++counts.back();
                    continue;
                }
                if (bs.isDelta) {
                    ++deltaCount;
                    ++counts.back();
                    continue;
                }
                ++counts[size_t(cellOf(toBinFrame(bs.wiWorld)))];
                float pdf = bsdf.pdfFwdW(wo, bs.wiWorld);
                Rgb expectW = bsdf.eval(wo, bs.wiWorld, TransportMode::Radiance) * std::abs(bs.wiWorld.z) / pdf;
                if (!(std::abs(pdf - bs.pdfFwdW) <= 1e-3f * pdf)) ++badPdf;
                if (!(glm::length(expectW - bs.weight) <= 1e-3f * glm::length(expectW) + 1e-6f)) ++badWeight;
            }
            std::string what = std::string(pt.name) + " theta " + std::to_string(int(theta));
            EXPECT_LE(badPdf, n / 10000) << what;
            EXPECT_LE(badWeight, n / 10000) << what;
            if (pt.roughness > 0.f) {
                EXPECT_EQ(deltaCount, 0) << what;
            } else if (theta < 90.f) {
                EXPECT_GT(deltaCount, 0) << what << ": the smooth coat is never sampled";
            }
            std::vector<double> prob = integrateCells([&](const Vec3f& w) { return double(bsdf.pdfFwdW(wo, fromBinFrame(w))); }, 24);
            double pv = chi2Test(counts, prob, n, what);
            EXPECT_GT(pv, sidakLevel()) << what;
        }
    }
}

// Reflection is symmetric; refraction obeys f(wo→wi) = f*(wi→wo), the adjoint being the importance
// mode (f/η_o² = f*/η_i², Veach 1997, eq. 5.14): evalBsdf(wo, wi, radiance) = evalBsdf(wi, wo, importance).
TEST(GltfBsdf, ReciprocityWithTheEtaSquaredRuleOfRefraction) {
    // Float rounding: the generalized half vector of a refraction cancels near grazing microfacets,
    // so a few pairs per thousand miss 1e-3; a wrong rule misses on every pair.
    Pcg32 rng(3, 4);
    for (const Point& pt : kChi2Points) {
        BsdfParams p = makeParams(pt);
        int checked = 0, bad = 0, refractions = 0, badEta = 0;
        for (int i = 0; i < 20000; ++i) {
            Vec3f wo = sampleUniformSphere(rng.next2D()), wi = sampleUniformSphere(rng.next2D());
            Rgb f = evalBsdf(p, wo, wi, TransportMode::Radiance);
            if (isBlack(f)) continue;
            ++checked;
            Rgb fAdj = evalBsdf(p, wi, wo, TransportMode::Importance);
            if (!(glm::length(f - fAdj) <= 1e-3f * glm::length(f))) ++bad;
            Rgb fSwap = evalBsdf(p, wi, wo, TransportMode::Radiance);
            // Reflection (and a thin wall) is symmetric; the radiance BTDF of a refraction is not:
            // swapping the directions multiplies it by (η_wi-side / η_wo-side)².
            float expected = 1.f;
            if (wo.z * wi.z < 0.f && !p.thinWalled) {
                ++refractions;
                expected = wo.z > 0.f ? sqr(p.ior) : 1.f / sqr(p.ior);
            }
            if (!(glm::length(fSwap - expected * f) <= 1e-3f * glm::length(expected * f))) ++badEta;
        }
        EXPECT_GT(checked, 2000) << pt.name;
        EXPECT_LE(bad, checked / 200) << pt.name << ": f(wo, wi) != f*(wi, wo)";
        EXPECT_LE(badEta, checked / 200) << pt.name << ": the eta^2 rule of refraction";
        if (pt.transmission > 0.f && !pt.thin) {
            EXPECT_GT(refractions, 500) << pt.name;
        }
    }
}

// White furnace of the BSDF: the directional albedo ∫ f*(wo, wi) |cos θi| dωi (importance mode: the
// physical flux leaving for light arriving from wo) is ≤ 1 for base colour 1 at every roughness and
// angle. Estimated as the mean sample weight (delta lobes included), with its standard error.
TEST(GltfBsdf, WhiteFurnaceAlbedoAtMostOneAndTheLossPerRoughness) {
    const int n = 40000;
    const float roughness[] = {0.f, 0.1f, 0.25f, 0.5f, 0.75f, 1.f};
    const float angles[] = {0.f, 30.f, 60.f, 80.f, 89.f};
    struct Case {
        const char* name;
        Point pt;
        bool inside;
    };
    const Case cases[] = {
        {"dielectric (plastic)", {"", Rgb(1.f), 0.f, 0.f}, false},
        {"metal", {"", Rgb(1.f), 1.f, 0.f}, false},
        {"glass volume, outside", {"", Rgb(1.f), 0.f, 0.f, 1.f, 1.f, false}, false},
        {"glass volume, inside", {"", Rgb(1.f), 0.f, 0.f, 1.f, 1.f, false}, true},
        {"thin-walled transmission", {"", Rgb(1.f), 0.f, 0.f, 1.f, 1.f, true}, false},
    };
    std::printf("[ furnace  ] directional albedo for base colour 1 (loss = 1 - albedo), angles %g/%g/%g/%g/%g deg\n",
                angles[0], angles[1], angles[2], angles[3], angles[4]);
    for (const Case& c : cases) {
        for (float r : roughness) {
            Point pt = c.pt;
            pt.roughness = r;
            BsdfParams p = forcePbr(makeParams(pt));
            std::printf("[ furnace  ] %-26s roughness %.2f:", c.name, r);
            for (float theta : angles) {
                Vec3f wo = direction(c.inside ? 180.f - theta : theta, 30.f);
                Pcg32 rng(uint64_t(theta) + 100, uint64_t(r * 100.f) + 1);
                double sum = 0.0, sum2 = 0.0;
                for (int i = 0; i < n; ++i) {
                    BsdfSample bs;
                    float uLobe = rng.nextFloat();
                    Vec2f u = rng.next2D();
                    if (!sampleBsdf(p, wo, uLobe, u, TransportMode::Importance, bs)) continue;
                    double w = bs.weight.g;
                    ASSERT_TRUE(std::isfinite(w) && w >= 0.0) << c.name;
                    sum += w;
                    sum2 += w * w;
                }
                double mean = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
                EXPECT_LE(mean, 1.0 + 4.0 * se + 1e-4) << c.name << " roughness " << r << " theta " << theta;
                std::printf(" %.3f", 1.0 - mean);
            }
            std::printf("\n");
        }
    }
}

// The special cases are the limits of the glTF model, not other materials: specular 0 is Lambert
// exactly, metallic 1 at roughness 0 is the mirror, smooth glass is the smooth dielectric (the same
// throughput per lobe), and a barely rough surface scatters like the smooth one.
TEST(GltfBsdf, SpecialCasesAreTheModelsLimits) {
    // Lambert: f = baseColor/π exactly.
    BsdfParams lambert = makeParams({"", Rgb(0.7f, 0.5f, 0.3f), 0.f, 0.8f, 0.f, 0.f});
    EXPECT_EQ(lambert.type, MaterialType::Diffuse);
    Pcg32 rng(8, 8);
    for (int i = 0; i < 200; ++i) {
        Vec3f wo = sampleCosineHemisphere(rng.next2D()), wi = sampleCosineHemisphere(rng.next2D());
        Rgb a = evalBsdf(lambert, wo, wi, TransportMode::Radiance);
        Rgb b = evalBsdf(forcePbr(lambert), wo, wi, TransportMode::Radiance);
        EXPECT_LE(glm::length(a - b), 1e-6f);
        EXPECT_NEAR(pdfBsdfW(lambert, wo, wi), pdfBsdfW(forcePbr(lambert), wo, wi), 1e-5f);
    }
    // Mirror and smooth glass: each delta lobe's throughput (weight × probability) agrees.
    BsdfParams mirror = makeParams({"", Rgb(0.9f, 0.6f, 0.3f), 1.f, 0.f});
    BsdfParams glass = makeParams({"", Rgb(0.9f, 1.f, 0.8f), 0.f, 0.f, 1.f, 1.f, false});
    EXPECT_EQ(mirror.type, MaterialType::Mirror);
    EXPECT_EQ(glass.type, MaterialType::Dielectric);
    EXPECT_TRUE(isDeltaMaterial(mirror) && isDeltaMaterial(glass) && isDeltaMaterial(forcePbr(glass)));
    for (const BsdfParams& special : {mirror, glass}) {
        for (float theta : {5.f, 50.f, 85.f, 120.f, 170.f}) {
            Vec3f wo = direction(theta, 40.f);
            for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
                Rgb throughputSpecial[2] = {Rgb(0.f), Rgb(0.f)}, throughputPbr[2] = {Rgb(0.f), Rgb(0.f)};
                for (float uLobe = 0.0005f; uLobe < 1.f; uLobe += 0.001f) {
                    BsdfSample a, b;
                    if (sampleBsdf(special, wo, uLobe, Vec2f(0.3f, 0.6f), mode, a))
                        throughputSpecial[a.wiLocal.z * wo.z > 0.f ? 0 : 1] += a.weight * 0.001f;
                    if (sampleBsdf(forcePbr(special), wo, uLobe, Vec2f(0.3f, 0.6f), mode, b)) {
                        EXPECT_TRUE(b.isDelta);
                        throughputPbr[b.wiLocal.z * wo.z > 0.f ? 0 : 1] += b.weight * 0.001f;
                    }
                }
                for (int k = 0; k < 2; ++k)
                    EXPECT_LE(glm::length(throughputSpecial[k] - throughputPbr[k]), 0.01f * glm::length(throughputSpecial[k]) + 1e-3f)
                        << "type " << int(special.type) << " theta " << theta << " lobe " << k;
            }
        }
    }
    // Roughness just above the delta threshold: the same albedo as the delta limit (within 1%).
    for (Point pt : {Point{"", Rgb(0.8f, 0.5f, 0.2f), 0.f, 0.f}, Point{"", Rgb(1.f), 0.f, 0.f, 1.f, 1.f, false}}) {
        for (float theta : {20.f, 70.f}) {
            double albedo[2];
            for (int k = 0; k < 2; ++k) {
                pt.roughness = k == 0 ? 0.f : std::sqrt(1.5f * kMinAlpha);
                BsdfParams p = forcePbr(makeParams(pt));
                Pcg32 r2(1, 2);
                double sum = 0.0;
                const int n = 100000;
                for (int i = 0; i < n; ++i) {
                    BsdfSample bs;
                    float uLobe = r2.nextFloat();
                    if (sampleBsdf(p, direction(theta), uLobe, r2.next2D(), TransportMode::Importance, bs)) sum += bs.weight.g;
                }
                albedo[k] = sum / n;
            }
            EXPECT_NEAR(albedo[0], albedo[1], 0.01 * albedo[0]) << "theta " << theta;
        }
    }
}

// KHR_materials_specular on a smooth coat: reflectance s·min(F0·specularColor, 1) head-on (F0 from
// the ior), rising to F90 = s at grazing; what the coat does not reflect (its maximum channel) goes
// straight through a thin wall, tinted by baseColor.
TEST(GltfBsdf, KhrSpecularScalesF0AndF90AndThinWallsTransmitTheRest) {
    const float s = 0.6f, ior = 1.7f;
    const Rgb tint(1.f, 0.5f, 0.25f), base(0.9f, 0.8f, 0.7f);
    const float f0 = sqr((ior - 1.f) / (ior + 1.f));
    BsdfParams p = makeParams({"", base, 0.f, 0.f, 1.f, s, true, ior, tint});
    ASSERT_EQ(p.type, MaterialType::Pbr);
    for (float theta : {0.f, 89.9f}) {
        Vec3f wo = direction(theta, 30.f);
        Rgb reflected(0.f), transmitted(0.f);
        for (float uLobe : {0.001f, 0.999f}) {
            BsdfSample bs;
            ASSERT_TRUE(sampleBsdf(p, wo, uLobe, Vec2f(0.5f), TransportMode::Radiance, bs));
            ASSERT_TRUE(bs.isDelta);
            (bs.wiLocal.z > 0.f ? reflected : transmitted) = bs.weight * bs.pdfW;  // the lobe's value
        }
        // The exact Fresnel curve's shape w between F0 (w = 0, head-on) and 1 (w → 1 at grazing).
        float w = (fresnelDielectric(wo.z, ior) - f0) / (1.f - f0);
        Rgb f0c = glm::min(Rgb(f0) * tint, Rgb(1.f));
        Rgb expectR = s * (f0c + (Rgb(1.f) - f0c) * w);
        if (theta == 0.f) EXPECT_NEAR(w, 0.f, 1e-6f);
        else EXPECT_GT(w, 0.98f);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(reflected[c], expectR[c], 1e-5f) << "theta " << theta;
        Rgb expectT = base * (1.f - maxComponent(reflected));
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(transmitted[c], expectT[c], 1e-4f) << "theta " << theta;
    }
}

TEST(GltfBsdf, TypeMappingAndDeltaFlags) {
    EXPECT_EQ(makeParams({"", Rgb(0.8f), 0.f, 1.f}).type, MaterialType::Pbr);  // plain baseColor: 4% coat
    EXPECT_EQ(makeParams({"", Rgb(0.8f), 1.f, 0.5f}).type, MaterialType::RoughConductor);
    EXPECT_EQ(makeParams({"", Rgb(1.f), 0.f, 0.f, 1.f, 1.f, true}).type, MaterialType::Pbr);  // thin glass
    EXPECT_EQ(makeParams({"", Rgb(1.f), 0.f, 0.3f, 1.f, 1.f, false}).type, MaterialType::Pbr);  // rough glass
    // Smooth plastic mixes a delta coat with a diffuse base: not a delta material, but some samples are.
    BsdfParams plastic = makeParams({"", Rgb(0.5f), 0.f, 0.f});
    EXPECT_FALSE(isDeltaMaterial(plastic));
    // Smooth thin-walled glass has only delta lobes; its transmission goes straight through.
    BsdfParams thin = makeParams({"", Rgb(1.f), 0.f, 0.f, 1.f, 1.f, true});
    EXPECT_TRUE(isDeltaMaterial(thin));
    Vec3f wo = direction(40.f, 10.f);
    for (float uLobe : {0.01f, 0.99f}) {
        BsdfSample bs;
        ASSERT_TRUE(sampleBsdf(thin, wo, uLobe, Vec2f(0.5f), TransportMode::Radiance, bs));
        EXPECT_TRUE(bs.isDelta);
        if (bs.wiLocal.z < 0.f) {
            EXPECT_LE(glm::length(bs.wiLocal + wo), 1e-5f);
            EXPECT_EQ(bs.eta, 1.f);
        }
    }
}

// SurfaceBsdf::sample(wo, sampler, ...) skips the numbers sampleBsdfReadsLobeChoice and
// sampleBsdfReadsDirection say a material does not read: for every material type, changing such a
// number changes nothing sampleBsdf returns (were one read after all, it would be a constant 0.5).
TEST(GltfBsdf, NumbersSaidUnreadChangeNoSample) {
    const BsdfParams materials[] = {
        makeParams({"", Rgb(0.7f, 0.5f, 0.3f), 0.f, 0.8f, 0.f, 0.f}),             // Lambertian
        makeParams({"", Rgb(0.9f, 0.6f, 0.3f), 1.f, 0.f}),                        // smooth mirror
        makeParams({"", Rgb(0.9f, 1.f, 0.8f), 0.f, 0.f, 1.f, 1.f, false}),        // smooth glass
        makeParams({"", Rgb(0.8f), 1.f, 0.5f}),                                   // rough metal
        makeParams({"", Rgb(0.8f, 0.3f, 0.2f), 0.f, 0.5f}),                       // the glTF model
        makeParams({"", Rgb(1.f), 0.f, 0.3f, 1.f, 1.f, false}),                   // rough glass (model)
    };
    bool seen[5] = {};
    Pcg32 rng(7, 3);
    for (const BsdfParams& m : materials) {
        seen[int(m.type)] = true;
        for (float theta : {20.f, 70.f, 150.f}) {
            Vec3f wo = direction(theta, 30.f);
            for (int k = 0; k < 200; ++k) {
                float uLobe = rng.nextFloat(), uLobe2 = rng.nextFloat();
                Vec2f u = rng.next2D(), u2 = rng.next2D();
                BsdfSample a, b;
                bool okA = sampleBsdf(m, wo, uLobe, u, TransportMode::Radiance, a);
                bool okB = sampleBsdf(m, wo, sampleBsdfReadsLobeChoice(m) ? uLobe : uLobe2, sampleBsdfReadsDirection(m) ? u : u2,
                                      TransportMode::Radiance, b);
                ASSERT_EQ(okA, okB) << "type " << int(m.type);
                if (!okA) continue;
                EXPECT_EQ(a.wiLocal, b.wiLocal) << "type " << int(m.type);
                EXPECT_EQ(a.pdfW, b.pdfW);
                EXPECT_EQ(a.weight, b.weight);
                EXPECT_EQ(a.isDelta, b.isDelta);
                EXPECT_EQ(a.eta, b.eta);
            }
        }
    }
    for (bool s : seen) EXPECT_TRUE(s) << "a material type is not covered";
}

// No NaN or Inf anywhere on a sweep of degenerate inputs: roughness 0 and 1 and the threshold,
// black and saturated base colours, ior 1 and 10, grazing and exactly tangent directions.
TEST(GltfBsdf, FiniteOnDegenerateInputs) {
    const float roughness[] = {0.f, 1e-3f, 0.0316f, 0.032f, 0.5f, 1.f};
    const float metallic[] = {0.f, 0.5f, 1.f};
    const Rgb bases[] = {Rgb(0.f), Rgb(1.f), Rgb(1.f, 0.f, 0.f)};
    const float transmission[] = {0.f, 0.5f, 1.f};
    const float specular[] = {0.f, 1.f};
    const float iors[] = {1.f, 1.0001f, 1.5f, 10.f};
    const Vec3f wos[] = {Vec3f(0.f, 0.f, 1.f), Vec3f(0.f, 0.f, -1.f), Vec3f(1.f, 0.f, 0.f), glm::normalize(Vec3f(1.f, 0.f, 1e-7f)),
                         glm::normalize(Vec3f(1.f, 0.f, -1e-7f)), direction(89.99f), direction(45.f), direction(135.f)};
    Pcg32 rng(17, 1);
    int evaluated = 0;
    for (float r : roughness)
        for (float m : metallic)
            for (const Rgb& c : bases)
                for (float t : transmission)
                    for (float s : specular)
                        for (float ior : iors)
                            for (bool thin : {false, true}) {
                                BsdfParams p = forcePbr(makeParams({"", c, m, r, t, s, thin, ior, Rgb(1.f, 0.3f, 0.f)}));
                                for (const Vec3f& wo : wos) {
                                    for (int i = 0; i < 4; ++i) {
                                        Vec3f wi = i == 0 ? -wo : i == 1 ? Vec3f(-wo.x, -wo.y, wo.z) : sampleUniformSphere(rng.next2D());
                                        for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
                                            Rgb f = evalBsdf(p, wo, wi, mode);
                                            float pdf = pdfBsdfW(p, wo, wi);
                                            ASSERT_TRUE(std::isfinite(f.r) && std::isfinite(f.g) && std::isfinite(f.b) && f.r >= 0.f && f.g >= 0.f &&
                                                        f.b >= 0.f)
                                                << "eval r " << r << " m " << m << " t " << t << " ior " << ior << " wo.z " << wo.z;
                                            ASSERT_TRUE(std::isfinite(pdf) && pdf >= 0.f) << "pdf r " << r << " ior " << ior << " wo.z " << wo.z;
                                            BsdfSample bs;
                                            if (sampleBsdf(p, wo, rng.nextFloat(), rng.next2D(), mode, bs)) {
                                                ASSERT_TRUE(std::isfinite(bs.weight.r) && std::isfinite(bs.weight.g) && std::isfinite(bs.weight.b) &&
                                                            bs.weight.r >= 0.f && bs.weight.g >= 0.f && bs.weight.b >= 0.f)
                                                    << "weight r " << r << " m " << m << " t " << t << " ior " << ior << " wo.z " << wo.z;
                                                ASSERT_TRUE(std::isfinite(bs.pdfW) && bs.pdfW > 0.f && std::isfinite(bs.eta) && bs.eta > 0.f);
                                                ASSERT_NEAR(glm::length(bs.wiLocal), 1.f, 1e-3f);
                                            }
                                            ++evaluated;
                                        }
                                    }
                                }
                            }
    EXPECT_GT(evaluated, 50000);
}

// The transport rules around the new BSDF, through the integrators: every integrator agrees with
// ptnee on a scene whose only light sits inside a rough glass ball (radiance leaves the dense
// medium, so the η² rule is not cancelled by a way back in; ptnee reaches the bulb by NEE from
// inside the ball and by BSDF sampling through it), next to plastic, rough thin-walled transmission
// and a half-metal. With a smooth plastic coat (delta over diffuse) pt and bdpt are compared; light
// tracing cannot see a delta coat from the camera, so lt gets the rough-plastic version.
// Standard errors from independent batches.
TEST(GltfBsdf, IntegratorsAgreeOnGltfMaterialsWithALightInsideRoughGlass) {
    auto makeScene = [](float plasticRoughness) {
        Scene scene;
        auto material = [&](const Point& pt, Rgb emission = Rgb(0.f)) {
            Material m;
            m.bsdf = makeParams(pt);
            m.emission = emission;
            m.doubleSided = true;
            scene.materials.push_back(m);
            return uint32_t(scene.materials.size() - 1);
        };
        uint32_t enclosure = material({"", Rgb(0.5f), 0.f, 1.f, 0.f, 0.f});
        uint32_t bulb = material({"", Rgb(0.f), 0.f, 1.f, 0.f, 0.f}, Rgb(5.f, 4.f, 3.f));
        uint32_t glass = material({"", Rgb(1.f, 0.95f, 0.9f), 0.f, 0.3f, 1.f, 1.f, false});
        uint32_t plastic = material({"", Rgb(0.8f, 0.2f, 0.2f), 0.f, plasticRoughness});
        uint32_t thin = material({"", Rgb(0.3f, 0.9f, 0.5f), 0.f, 0.4f, 0.8f, 1.f, true});
        uint32_t halfMetal = material({"", Rgb(0.9f, 0.7f, 0.4f), 0.5f, 0.5f});
        scene.geometry.spheres = {Sphere{"enclosure", Vec3f(0.f), 6.f, enclosure},
                                  Sphere{"glass", Vec3f(0.f, 0.f, -3.f), 1.f, glass},
                                  Sphere{"bulb", Vec3f(0.f, 0.f, -3.f), 0.6f, bulb},
                                  Sphere{"plastic", Vec3f(1.9f, 0.3f, -3.5f), 0.8f, plastic},
                                  Sphere{"thin", Vec3f(-1.9f, 0.3f, -3.5f), 0.8f, thin},
                                  Sphere{"half metal", Vec3f(0.f, -1.6f, -3.2f), 0.6f, halfMetal}};
        scene.finalize();
        scene.camera = CameraDesc{};
        scene.camera->yfov = 1.1f;
        return scene;
    };
    const int w = 16, h = 16, batches = 12;
    // Image mean over `batches` renders and its standard error from their spread.
    auto meanOf = [&](const Scene& scene, const char* name, int spp, uint64_t seed0, double mean[3], double se[3]) {
        double sum[3] = {0, 0, 0}, sumSq[3] = {0, 0, 0};
        for (int b = 0; b < batches; ++b) {
            RenderOptions opt{.spp = spp, .seed = seed0 + uint64_t(b), .tileSize = 16};
            double m[3], unused[3];
            test::pixelMean(test::renderScene(scene, name, w, h, opt).film, m, unused);
            for (int c = 0; c < 3; ++c) {
                sum[c] += m[c];
                sumSq[c] += m[c] * m[c];
            }
        }
        for (int c = 0; c < 3; ++c) {
            mean[c] = sum[c] / batches;
            se[c] = std::sqrt(std::max(0.0, (sumSq[c] / batches - mean[c] * mean[c]) / (batches - 1)));
        }
    };
    // The camera inside an emitting ball of smooth plastic: every vertex mixes a delta coat with a
    // diffuse base, and BDPT must still connect at vertices whose own walk took the coat.
    {
        Scene scene;
        Material m;
        m.bsdf = makeParams({"", Rgb(0.6f, 0.5f, 0.4f), 0.f, 0.f});
        m.emission = Rgb(1.f);
        m.doubleSided = true;
        scene.materials.push_back(m);
        scene.geometry.spheres.push_back(Sphere{"ball", Vec3f(0.1f, -0.2f, 0.05f), 1.f, 0});
        scene.finalize();
        scene.camera = CameraDesc{};
        scene.camera->yfov = 1.2f;
        double ref[3], refSe[3], mean[3], se[3];
        meanOf(scene, "ptnee", 16, 300, ref, refSe);
        meanOf(scene, "bdpt", 8, 400, mean, se);
        std::printf("[ agree    ] smooth plastic ball  bdpt %.4f (se %.4f)  ptnee %.4f (se %.4f)\n", mean[0], se[0], ref[0], refSe[0]);
        for (int c = 0; c < 3; ++c)
            EXPECT_LT(std::abs(mean[c] - ref[c]), std::max(4.5 * std::hypot(se[c], refSe[c]), 0.005 * ref[c]))
                << "smooth plastic ball, bdpt channel " << c << ": " << mean[c] << " vs ptnee " << ref[c];
    }
    for (float plasticRoughness : {0.f, 0.3f}) {
        Scene scene = makeScene(plasticRoughness);
        double ref[3], refSe[3];
        meanOf(scene, "ptnee", 64, 100, ref, refSe);
        std::vector<const char*> others = plasticRoughness == 0.f ? std::vector<const char*>{"pt", "bdpt"} : std::vector<const char*>{"lt"};
        for (const char* name : others) {
            double mean[3], se[3];
            meanOf(scene, name, std::string(name) == "bdpt" ? 16 : std::string(name) == "lt" ? 128 : 96, 200, mean, se);
            std::printf("[ agree    ] plastic roughness %.1f %-5s %.4f %.4f %.4f (se %.4f)  ptnee %.4f %.4f %.4f (se %.4f)\n", plasticRoughness,
                        name, mean[0], mean[1], mean[2], se[0], ref[0], ref[1], ref[2], refSe[0]);
            // 4.5 standard errors (estimated from 12 batches: Student's t with 11 degrees of freedom),
            // and never less than 0.5%: the bulb behind rough glass gives heavy-tailed batches.
            for (int c = 0; c < 3; ++c)
                EXPECT_LT(std::abs(mean[c] - ref[c]), std::max(4.5 * std::hypot(se[c], refSe[c]), 0.005 * ref[c]))
                    << name << " channel " << c << ": " << mean[c] << " vs ptnee " << ref[c];
        }
    }
}
