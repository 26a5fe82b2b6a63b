#include "materials/surface_bsdf.h"

namespace tessera {

bool SurfaceBsdf::sidesAgree(const Vec3f& wo, const Vec3f& wi) const {
    bool reflectShading = glm::dot(wo, frame_.n) * glm::dot(wi, frame_.n) > 0.f;
    bool reflectGeometric = glm::dot(wo, ng_) * glm::dot(wi, ng_) > 0.f;
    return reflectShading == reflectGeometric;
}

float SurfaceBsdf::shadingCorrection(const Vec3f& wo, const Vec3f& wi, TransportMode mode) const {
    if (mode == TransportMode::Radiance) return 1.f;
    // Veach 1997, §5.3: with shading normals the BSDF is not symmetric; the adjoint used for
    // importance (light sub-paths) is f*(wo→wi) = f(wi→wo) · |wo·ns| |wi·ng| / (|wo·ng| |wi·ns|).
    float num = std::abs(glm::dot(wo, frame_.n)) * std::abs(glm::dot(wi, ng_));
    float den = std::abs(glm::dot(wo, ng_)) * std::abs(glm::dot(wi, frame_.n));
    return den > 0.f ? num / den : 0.f;
}

Rgb SurfaceBsdf::eval(const Vec3f& wo, const Vec3f& wi, TransportMode mode) const {
    if (isDelta() || !sidesAgree(wo, wi)) return Rgb(0.f);
    // Reflection lobes are symmetric in their arguments; refraction is not, and evalBsdf returns
    // the adjoint for importance itself (the η² rule). The shading correction comes on top.
    Rgb f = evalBsdf(mat_, frame_.toLocal(wo), frame_.toLocal(wi), mode);
    return f * shadingCorrection(wo, wi, mode);
}

float SurfaceBsdf::pdfFwdW(const Vec3f& wo, const Vec3f& wi) const {
    if (isDelta() || !sidesAgree(wo, wi)) return 0.f;
    return pdfBsdfW(mat_, frame_.toLocal(wo), frame_.toLocal(wi));
}

void SurfaceBsdf::pdfBothW(const Vec3f& wo, const Vec3f& wi, float& pdfFwdW, float& pdfRevW) const {
    pdfFwdW = pdfRevW = 0.f;
    if (isDelta() || !sidesAgree(wo, wi)) return;
    Vec3f woL = frame_.toLocal(wo), wiL = frame_.toLocal(wi);
    pdfFwdW = pdfBsdfW(mat_, woL, wiL);
    pdfRevW = pdfBsdfW(mat_, wiL, woL);
}

Rgb SurfaceBsdf::evalWithPdf(const Vec3f& wo, const Vec3f& wi, TransportMode mode, float& pdfFwdW) const {
    pdfFwdW = 0.f;
    if (isDelta() || !sidesAgree(wo, wi)) return Rgb(0.f);
    Vec3f woL = frame_.toLocal(wo), wiL = frame_.toLocal(wi);
    return evalBsdfWithPdf(mat_, woL, wiL, mode, pdfFwdW) * shadingCorrection(wo, wi, mode);
}

bool SurfaceBsdf::sample(const Vec3f& wo, float uLobe, Vec2f u, TransportMode mode, SurfaceBsdfSample& out) const {
    Vec3f woL = frame_.toLocal(wo);
    BsdfSample bs;
    if (!sampleBsdf(mat_, woL, uLobe, u, mode, bs)) return false;
    Vec3f wi = frame_.toWorld(bs.wiLocal);
    if (!sidesAgree(wo, wi)) return false;
    out.wiWorld = wi;
    out.isDelta = bs.isDelta;
    out.eta = bs.eta;
    out.pdfFwdW = bs.pdfW;
    out.weight = bs.weight * shadingCorrection(wo, wi, mode);
    return true;
}

}  // namespace tessera
