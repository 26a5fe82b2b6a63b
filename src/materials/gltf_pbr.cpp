#include "materials/gltf_pbr.h"

#include <utility>

#include "core/sampling.h"
#include "materials/bsdf_local.h"

namespace tessera {
namespace {

using namespace bsdf_local;

/// Below this |cos θ| a direction counts as grazing: microfacet terms are 0 there (their
/// 1/(cos θo cos θi) would otherwise overflow while G₂ has not yet reached 0 in float).
constexpr float kMinCos = 1e-6f;
/// Least probability of the microfacet lobes when a diffuse base is present: their
/// selection weight is estimated at the macro normal, where it can vanish (black metal seen
/// head-on) while other microfacets still reflect.
constexpr float kMinMicrofacetProb = 0.1f;

/// What every call needs about the material seen from one wo, in the frame flipped so that
/// wo.z > 0 (all lobes are two-sided; only a refracting volume tells inside from outside).
struct Pbr {
    const BsdfParams& p;
    Vec3f wo;
    float eta = 1.f;          ///< η_t / η_i seen from wo's side
    float f0 = 0.f;           ///< dielectric F0 = ((η − 1)/(η + 1))², the same from both sides
    float alpha = kMinAlpha;  ///< GGX α of the rough lobes
    bool smooth = false;      ///< α < kMinAlpha: coat, metal and BTDF are delta lobes
    bool refracts = false;    ///< transmission into a closed volume (else thin-walled)
    bool plainFresnel = true; ///< specular 1, specularColor 1: F_d is the Fresnel reflectance itself
    bool hasDiffuse = false;
    bool hasTransmission = false;
    float diffuseNorm = 1.f;  ///< 1 / (1 − F_avg) outside; 1 inside a volume (where TIR dominates F_avg)
    float pDiffuse = 0.f;     ///< probability of sampling the diffuse lobe (the rest: microfacet lobes)

    Pbr(const BsdfParams& params, const Vec3f& woIn) : p(params) {
        float flip = woIn.z < 0.f ? -1.f : 1.f;
        wo = Vec3f(woIn.x, woIn.y, woIn.z * flip);
        refracts = p.transmission > 0.f && !p.thinWalled && p.metallic < 1.f;
        // A rough interface of ior 1 is a delta (straight through): evaluated at ior 1.001, an
        // almost-delta lobe whose densities stay finite in float.
        float ior = refracts && p.alpha >= kMinAlpha ? std::max(p.ior, 1.001f) : p.ior;
        eta = refracts && flip < 0.f ? 1.f / ior : ior;
        f0 = sqr((ior - 1.f) / (ior + 1.f));
        smooth = p.alpha < kMinAlpha;
        alpha = std::max(p.alpha, kMinAlpha);
        plainFresnel = p.specular == 1.f && p.specularColor == Rgb(1.f);
        hasDiffuse = p.metallic < 1.f && p.transmission < 1.f && maxComponent(p.baseColor) > 0.f;
        hasTransmission = p.metallic < 1.f && p.transmission > 0.f && maxComponent(p.baseColor) > 0.f;
        if (!(refracts && flip < 0.f) && p.coatFresnelAvg < 1.f) diffuseNorm = 1.f / (1.f - p.coatFresnelAvg);
        pDiffuse = diffuseProbability();
    }

    /// The dielectric coat's reflectance F_d at cos θ (> 0, on wo's side): KHR_materials_specular's
    /// F0 and F90 scaling applied to the exact Fresnel curve. Total internal reflection reflects all.
    Rgb coatFresnel(float cosTheta) const {
        float F = fresnelDielectric(cosTheta, eta);
        if (plainFresnel || F >= 1.f) return Rgb(F);
        float w = f0 < 1.f ? std::clamp((F - f0) / (1.f - f0), 0.f, 1.f) : 1.f;
        Rgb f0c = glm::min(Rgb(f0) * p.specularColor, Rgb(1.f));
        return p.specular * (f0c + (Rgb(1.f) - f0c) * w);
    }
    /// What the coat lets through at cos θ, the weight of the base (diffuse and BTDF) there.
    float coatTransmittance(float cosTheta) const { return 1.f - maxComponent(coatFresnel(cosTheta)); }

    /// Reflectance of the specular (metal + coat) layer on a microfacet with wo·h = cosOH.
    Rgb specularReflectance(float cosOH, const Rgb& coatF) const {
        return p.metallic * fresnelSchlick(p.baseColor, cosOH) + (1.f - p.metallic) * coatF;
    }
    /// Scalar weight of the base's transmission on a microfacet (times baseColor in f).
    float transmissionWeight(const Rgb& coatF) const {
        return hasTransmission ? (1.f - p.metallic) * p.transmission * (1.f - maxComponent(coatF)) : 0.f;
    }
    /// Probability of choosing reflection on a microfacet: the lobes' estimated albedos there.
    /// Zero exactly when the reflection is black, one when the transmission is.
    float reflectProbability(const Rgb& reflectance, float transmission) const {
        float r = average(reflectance), t = transmission * average(p.baseColor);
        return r + t > 0.f ? r / (r + t) : -1.f;  // -1: nothing scatters on this microfacet
    }

    float diffuseProbability() const {
        if (!hasDiffuse) return 0.f;
        Rgb coatF = coatFresnel(wo.z);
        float wDiffuse = (1.f - p.metallic) * (1.f - p.transmission) * average(p.baseColor) * (1.f - maxComponent(coatF)) * diffuseNorm;
        if (wDiffuse <= 0.f) return 0.f;  // f_diffuse(wo, ·) = 0 at this wo
        float wMicro = average(specularReflectance(wo.z, coatF)) + transmissionWeight(coatF) * average(p.baseColor);
        bool microPresent = p.metallic > 0.f || (p.specular > 0.f && p.ior != 1.f) || hasTransmission;
        if (!microPresent) return 1.f;
        float pd = wDiffuse / (wDiffuse + wMicro);
        return smooth ? pd : std::min(pd, 1.f - kMinMicrofacetProb);
    }

    Rgb diffuseF(const Vec3f& wi) const {
        if (!hasDiffuse || wi.z <= 0.f) return Rgb(0.f);
        float k = (1.f - p.metallic) * (1.f - p.transmission) * coatTransmittance(wo.z) * coatTransmittance(wi.z) * diffuseNorm;
        return p.baseColor * (k * kInvPi);
    }

    /// The rough microfacet lobes at wi: their f and their share of the sampling density.
    void microfacet(const Vec3f& wi, TransportMode mode, Rgb& f, float& pdfW) const {
        f = Rgb(0.f);
        pdfW = 0.f;
        if (smooth || wo.z < kMinCos || std::abs(wi.z) < kMinCos) return;
        bool reflect = wi.z > 0.f;
        if (!reflect && !hasTransmission) return;
        // Half vector: of the reflection, of the mirror image for thin walls, or Walter et al.'s
        // generalized one for refraction (eq. 16), turned to wo's side.
        Vec3f h = reflect ? wo + wi : refracts ? wo + eta * wi : wo + flipZ(wi);
        float len2 = glm::dot(h, h);
        if (!(len2 > 0.f)) return;
        h /= std::sqrt(len2);
        if (h.z < 0.f) h = -h;
        // Backfacing microfacets scatter nothing (the χ⁺ terms of Walter 2007, eqs. 20 and 21); a
        // thin wall's transmission is tested as the reflection it mirrors.
        float cosOH = glm::dot(wo, h);
        float cosIH = glm::dot(reflect || refracts ? wi : flipZ(wi), h);
        if (cosOH <= 0.f || (reflect || !refracts ? cosIH <= 0.f : cosIH >= 0.f)) return;
        float D = ggx::D(h, alpha);
        float lo = ggx::lambda(wo, alpha), li = ggx::lambda(wi, alpha);
        float G2 = 1.f / (1.f + lo + li);
        // Visible-normal density of h (Heitz 2018, eq. 3): G1(wo) max(0, wo·h) D(h) / cos θo.
        float pdfH = cosOH * D / ((1.f + lo) * wo.z);
        Rgb coatF = coatFresnel(cosOH);
        Rgb reflectance = specularReflectance(cosOH, coatF);
        float tw = transmissionWeight(coatF);
        float pR = reflectProbability(reflectance, tw);
        if (pR < 0.f) return;
        float pMicro = 1.f - pDiffuse;
        float absCosI = std::abs(wi.z);
        if (reflect) {
            f = reflectance * (D * G2 / (4.f * wo.z * absCosI));
            pdfW = pMicro * pR * pdfH / (4.f * cosOH);  // reflection Jacobian 1/(4 wo·h) (Walter eq. 14)
        } else if (!refracts) {
            // Thin wall: the reflection lobe mirrored through the surface (same Jacobian).
            f = p.baseColor * (tw * D * G2 / (4.f * wo.z * absCosI));
            pdfW = pMicro * (1.f - pR) * pdfH / (4.f * cosOH);
        } else {
            // Walter et al. 2007, eqs. 17 and 21 (pbrt-v4's form with η = η_t/η_i from wo's side).
            float denom = sqr(cosIH + cosOH / eta);
            float ft = D * G2 * std::abs(cosIH * cosOH) / (denom * wo.z * absCosI);
            // Radiance is compressed by (η_i/η_t)² on refraction; importance is not (Veach 1997, §5.2).
            if (mode == TransportMode::Radiance) ft /= eta * eta;
            f = p.baseColor * (tw * ft);
            pdfW = pMicro * (1.f - pR) * pdfH * std::abs(cosIH) / denom;
        }
    }
};

}  // namespace

bool pbrHasNonDeltaLobe(const BsdfParams& m) {
    return m.alpha >= kMinAlpha || (m.metallic < 1.f && m.transmission < 1.f && maxComponent(m.baseColor) > 0.f);
}

float pbrCoatFresnelAverage(const BsdfParams& m) {
    if (!(m.metallic < 1.f && m.transmission < 1.f)) return 0.f;  // no diffuse base to normalize
    // ∫₀¹ max F_d(µ) 2µ dµ by 8-point Gauss–Legendre (abscissae and weights of Abramowitz & Stegun,
    // Table 25.4) on [0, 0.2] and [0.2, 1]: the reflectance rises steeply only near grazing; the
    // error stays below 1e-5 for ior 1.01 … 10.
    static constexpr double kX[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
    static constexpr double kW[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
    BsdfParams outside = m;
    outside.thinWalled = true;  // seen from outside: η as given
    Pbr b(outside, Vec3f(0.f, 0.f, 1.f));
    double sum = 0.0;
    for (auto [lo, hi] : {std::pair{0.0, 0.2}, std::pair{0.2, 1.0}})
        for (int i = 0; i < 4; ++i)
            for (double sign : {-1.0, 1.0}) {
                double mu = lo + (hi - lo) * 0.5 * (1.0 + sign * kX[i]);
                sum += (hi - lo) * 0.5 * kW[i] * 2.0 * mu * maxComponent(b.coatFresnel(float(mu)));
            }
    return float(sum);
}

Rgb evalPdfPbr(const BsdfParams& m, const Vec3f& woIn, const Vec3f& wiIn, TransportMode mode, float& pdfW) {
    pdfW = 0.f;
    if (woIn.z == 0.f) return Rgb(0.f);
    Pbr b(m, woIn);
    Vec3f wi = woIn.z < 0.f ? flipZ(wiIn) : wiIn;
    Rgb f;
    b.microfacet(wi, mode, f, pdfW);
    if (b.hasDiffuse) pdfW += b.pDiffuse * cosineHemispherePdfW(wi.z);
    return f + b.diffuseF(wi);
}

Rgb evalPbr(const BsdfParams& m, const Vec3f& woIn, const Vec3f& wiIn, TransportMode mode) {
    float pdfW;
    return evalPdfPbr(m, woIn, wiIn, mode, pdfW);
}

float pdfPbr(const BsdfParams& m, const Vec3f& woIn, const Vec3f& wiIn) {
    float pdfW;
    evalPdfPbr(m, woIn, wiIn, TransportMode::Radiance, pdfW);
    return pdfW;
}

bool samplePbr(const BsdfParams& m, const Vec3f& woIn, float uLobe, Vec2f u, TransportMode mode, BsdfSample& out) {
    if (woIn.z == 0.f) return false;
    Pbr b(m, woIn);
    const Vec3f& wo = b.wo;
    float flip = woIn.z < 0.f ? -1.f : 1.f;
    out.eta = 1.f;
    Vec3f wi;
    if (uLobe < b.pDiffuse) {
        wi = sampleCosineHemisphere(u);
    } else {
        // The microfacet lobes share one microfacet normal: sample it, then reflect or transmit
        // with the probability of the lobes' albedos on it (uLobe reused, rescaled).
        float pMicro = 1.f - b.pDiffuse;
        float uChoice = std::min((uLobe - b.pDiffuse) / pMicro, 0x1.fffffep-1f);
        Vec3f h = b.smooth ? Vec3f(0.f, 0.f, 1.f) : ggx::sampleVisibleNormal(wo, b.alpha, u);
        float cosOH = glm::dot(wo, h);
        if (cosOH <= 0.f) return false;
        Rgb coatF = b.coatFresnel(cosOH);
        Rgb reflectance = b.specularReflectance(cosOH, coatF);
        float tw = b.transmissionWeight(coatF);
        float pR = b.reflectProbability(reflectance, tw);
        if (pR < 0.f) return false;
        bool reflect = uChoice < pR;
        if (reflect) {
            wi = glm::reflect(-wo, h);
            if (wi.z <= 0.f) return false;
        } else if (b.refracts) {
            if (!refractAbout(wo, h, b.eta, wi) || wi.z >= 0.f) return false;
            out.eta = b.eta;
        } else {
            wi = flipZ(glm::reflect(-wo, h));  // thin wall: straight through when smooth
            if (wi.z >= 0.f) return false;
        }
        if (b.smooth) {
            // A delta lobe: its throughput over the discrete probability of choosing it.
            float prob = pMicro * (reflect ? pR : 1.f - pR);
            Rgb value = reflect ? reflectance : m.baseColor * tw;
            if (!reflect && b.refracts && mode == TransportMode::Radiance) value /= b.eta * b.eta;
            out.wiLocal = Vec3f(wi.x, wi.y, wi.z * flip);
            out.pdfW = prob;
            out.weight = value / prob;
            out.isDelta = true;
            return true;
        }
    }
    // A non-delta lobe: weight by the whole mixture, f / (Σ_lobes p_lobe pdf_lobe), so that the
    // sample's density is exactly pdfPbr (one-sample MIS over the lobes, Veach 1997, §9.2.4).
    Rgb f;
    float pdfW;
    b.microfacet(wi, mode, f, pdfW);
    f += b.diffuseF(wi);
    if (b.hasDiffuse) pdfW += b.pDiffuse * cosineHemispherePdfW(wi.z);
    if (!(pdfW > 0.f)) return false;
    out.wiLocal = Vec3f(wi.x, wi.y, wi.z * flip);
    out.pdfW = pdfW;
    out.weight = f * (std::abs(wi.z) / pdfW);
    out.isDelta = false;
    return true;
}

}  // namespace tessera
