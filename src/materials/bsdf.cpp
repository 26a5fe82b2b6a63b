#include "materials/bsdf.h"

#include "core/sampling.h"
#include "materials/bsdf_local.h"
#include "materials/gltf_pbr.h"

namespace tessera {
namespace {

using namespace bsdf_local;

inline float alphaOf(const BsdfParams& m) { return std::max(m.alpha, kMinAlpha); }

}  // namespace

float fresnelDielectric(float cosThetaI, float eta) {
    cosThetaI = std::clamp(cosThetaI, -1.f, 1.f);
    if (cosThetaI < 0.f) {
        eta = 1.f / eta;
        cosThetaI = -cosThetaI;
    }
    float sin2T = (1.f - cosThetaI * cosThetaI) / (eta * eta);
    if (sin2T >= 1.f) return 1.f;  // total internal reflection
    float cosT = safeSqrt(1.f - sin2T);
    float rParl = (eta * cosThetaI - cosT) / (eta * cosThetaI + cosT);
    float rPerp = (cosThetaI - eta * cosT) / (cosThetaI + eta * cosT);
    return 0.5f * (rParl * rParl + rPerp * rPerp);
}

namespace ggx {
float D(const Vec3f& wm, float alpha) {
    float t2 = tan2Theta(wm);
    if (std::isinf(t2) || wm.z <= 0.f) return 0.f;
    float c4 = cos2Theta(wm) * cos2Theta(wm);
    float e = 1.f + t2 / (alpha * alpha);
    return 1.f / (kPi * alpha * alpha * c4 * e * e);
}
float lambda(const Vec3f& w, float alpha) {
    float t2 = tan2Theta(w);
    if (std::isinf(t2)) return 0.f;
    return 0.5f * (std::sqrt(1.f + alpha * alpha * t2) - 1.f);
}
Vec3f sampleVisibleNormal(const Vec3f& wo, float alpha, Vec2f u) {
    // Section 3 of the paper: stretch to the hemisphere configuration, sample the projected area of
    // the visible hemisphere (a disk warped towards the half facing wo), unstretch.
    Vec3f vh = glm::normalize(Vec3f(alpha * wo.x, alpha * wo.y, wo.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    Vec3f t1 = lensq > 0.f ? Vec3f(-vh.y, vh.x, 0.f) / std::sqrt(lensq) : Vec3f(1.f, 0.f, 0.f);
    Vec3f t2 = glm::cross(vh, t1);
    float r = std::sqrt(u.x);
    float phi = 2.f * kPi * u.y;
    float p1 = r * std::cos(phi);
    float p2 = r * std::sin(phi);
    float s = 0.5f * (1.f + vh.z);
    p2 = (1.f - s) * safeSqrt(1.f - p1 * p1) + s * p2;
    Vec3f nh = p1 * t1 + p2 * t2 + safeSqrt(1.f - p1 * p1 - p2 * p2) * vh;
    return glm::normalize(Vec3f(alpha * nh.x, alpha * nh.y, std::max(1e-6f, nh.z)));
}
}  // namespace ggx

void finalizeBsdfParams(BsdfParams& p) {
    bool smooth = p.alpha < kMinAlpha;
    if (p.metallic == 0.f && p.transmission == 0.f && p.specular == 0.f) p.type = MaterialType::Diffuse;
    else if (p.metallic == 1.f) p.type = smooth ? MaterialType::Mirror : MaterialType::RoughConductor;
    else if (p.metallic == 0.f && p.transmission == 1.f && smooth && !p.thinWalled && p.specular == 1.f && p.specularColor == Rgb(1.f))
        p.type = MaterialType::Dielectric;
    else p.type = MaterialType::Pbr;
    p.coatFresnelAvg = p.type == MaterialType::Pbr ? pbrCoatFresnelAverage(p) : 0.f;
}

Rgb evalBsdf(const BsdfParams& m, const Vec3f& woIn, const Vec3f& wiIn, TransportMode mode) {
    if (m.type == MaterialType::Pbr) return evalPbr(m, woIn, wiIn, mode);
    if (m.type == MaterialType::Diffuse) return lambertEval(m.baseColor, woIn.z, wiIn.z);
    if (woIn.z == 0.f) return Rgb(0.f);
    // Two-sided: mirror the frame so that wo is above the surface.
    float flip = woIn.z < 0.f ? -1.f : 1.f;
    Vec3f wo(woIn.x, woIn.y, woIn.z * flip), wi(wiIn.x, wiIn.y, wiIn.z * flip);
    switch (m.type) {
    case MaterialType::RoughConductor: {
        if (wi.z <= 0.f) return Rgb(0.f);
        Vec3f wm = wi + wo;
        if (glm::dot(wm, wm) == 0.f) return Rgb(0.f);
        wm = glm::normalize(wm);
        float a = alphaOf(m);
        float G = 1.f / (1.f + ggx::lambda(wo, a) + ggx::lambda(wi, a));
        Rgb F = fresnelSchlick(m.baseColor, std::abs(glm::dot(wi, wm)));
        return ggx::D(wm, a) * G * F / (4.f * wo.z * wi.z);
    }
    case MaterialType::Mirror:
    case MaterialType::Dielectric:
    case MaterialType::Diffuse:  // dispatched above
    case MaterialType::Pbr:
        return Rgb(0.f);
    }
    return Rgb(0.f);
}

float pdfBsdfW(const BsdfParams& m, const Vec3f& woIn, const Vec3f& wiIn) {
    if (m.type == MaterialType::Pbr) return pdfPbr(m, woIn, wiIn);
    if (m.type == MaterialType::Diffuse) return lambertPdfW(woIn.z, wiIn.z);
    if (woIn.z == 0.f) return 0.f;
    float flip = woIn.z < 0.f ? -1.f : 1.f;
    Vec3f wo(woIn.x, woIn.y, woIn.z * flip), wi(wiIn.x, wiIn.y, wiIn.z * flip);
    switch (m.type) {
    case MaterialType::RoughConductor: {
        if (wi.z <= 0.f) return 0.f;
        Vec3f wm = wi + wo;
        if (glm::dot(wm, wm) == 0.f) return 0.f;
        wm = glm::normalize(wm);
        float a = alphaOf(m);
        // Visible-normal density D_wo(wm) = G1(wo) max(0, wo·wm) D(wm) / cos θo, times the reflection
        // Jacobian 1 / (4 wo·wm) (Heitz 2018, eqs. 1 and 17).
        float g1 = 1.f / (1.f + ggx::lambda(wo, a));
        return g1 * ggx::D(wm, a) / (4.f * wo.z);
    }
    case MaterialType::Mirror:
    case MaterialType::Dielectric:
    case MaterialType::Diffuse:  // dispatched above
    case MaterialType::Pbr:
        return 0.f;
    }
    return 0.f;
}

Rgb evalBsdfWithPdf(const BsdfParams& m, const Vec3f& woLocal, const Vec3f& wiLocal, TransportMode mode, float& pdfW) {
    if (m.type == MaterialType::Pbr) return evalPdfPbr(m, woLocal, wiLocal, mode, pdfW);
    pdfW = pdfBsdfW(m, woLocal, wiLocal);
    return evalBsdf(m, woLocal, wiLocal, mode);
}

bool sampleBsdf(const BsdfParams& m, const Vec3f& woIn, float uLobe, Vec2f u, TransportMode mode, BsdfSample& out) {
    if (m.type == MaterialType::Pbr) return samplePbr(m, woIn, uLobe, u, mode, out);
    if (woIn.z == 0.f) return false;
    float flip = woIn.z < 0.f ? -1.f : 1.f;
    Vec3f wo(woIn.x, woIn.y, woIn.z * flip);
    Vec3f wi;
    switch (m.type) {
    case MaterialType::Diffuse: {
        wi = sampleCosineHemisphere(u);
        if (wi.z <= 0.f) return false;
        out.pdfW = cosineHemispherePdfW(wi.z);
        out.weight = m.baseColor;  // (albedo/π)·cos θ / (cos θ/π)
        out.isDelta = false;
        break;
    }
    case MaterialType::Mirror: {
        wi = reflectLocal(wo);
        out.pdfW = 1.f;
        out.weight = fresnelSchlick(m.baseColor, wo.z);
        out.isDelta = true;
        break;
    }
    case MaterialType::Dielectric: {
        // Undo the two-sided flip: which side of the interface wo is on decides η.
        Vec3f woReal = woIn;
        float F = fresnelDielectric(woReal.z, m.ior);
        out.isDelta = true;
        if (uLobe < F) {
            out.wiLocal = reflectLocal(woReal);
            out.pdfW = F;
            out.weight = Rgb(1.f);
            out.eta = 1.f;
            return true;
        }
        bool entering = woReal.z > 0.f;
        float eta = entering ? m.ior : 1.f / m.ior;  // η_t / η_i as seen from wo's side
        Vec3f woN = entering ? woReal : Vec3f(woReal.x, woReal.y, -woReal.z);
        Vec3f wt;
        if (!refractLocal(woN, eta, wt)) return false;  // cannot happen when F < 1
        if (!entering) wt.z = -wt.z;
        out.wiLocal = wt;
        out.pdfW = 1.f - F;
        // Radiance is compressed by (η_i/η_t)² on refraction; importance is not (Veach 1997, §5.2).
        out.weight = m.baseColor * (mode == TransportMode::Radiance ? 1.f / (eta * eta) : 1.f);
        out.eta = eta;
        return true;
    }
    case MaterialType::Pbr:  // dispatched above
        return false;
    case MaterialType::RoughConductor: {
        float a = alphaOf(m);
        Vec3f wm = ggx::sampleVisibleNormal(wo, a, u);
        wi = glm::reflect(-wo, wm);
        if (wi.z <= 0.f) return false;
        float g1o = 1.f / (1.f + ggx::lambda(wo, a));
        float G = 1.f / (1.f + ggx::lambda(wo, a) + ggx::lambda(wi, a));
        out.pdfW = g1o * ggx::D(wm, a) / (4.f * wo.z);
        // f cos/pdf = F · G / G1(wo) for visible-normal sampling (Heitz 2018, eq. 19).
        out.weight = fresnelSchlick(m.baseColor, std::abs(glm::dot(wi, wm))) * (G / g1o);
        out.isDelta = false;
        break;
    }
    }
    out.wiLocal = Vec3f(wi.x, wi.y, wi.z * flip);
    return true;
}

}  // namespace tessera
