#pragma once
/// \file bsdf.h
/// BSDF evaluation and sampling in the local shading frame (z = shading normal). Directions point
/// away from the surface: `woLocal` towards the previous vertex, `wiLocal` towards the next.
/// All BSDFs are two-sided: the frame is mirrored when wo lies below the shading normal.
#include "core/math.h"
#include "core/sampling.h"
#include "materials/material.h"

namespace tessera {

struct BsdfSample {
    Vec3f wiLocal{0.f};
    Rgb weight{0.f};   ///< f · |cos θi| / pdfW (or the delta lobe's throughput)
    float pdfW = 0.f;  ///< solid-angle density; for delta lobes the discrete probability of the lobe
    bool isDelta = false;
    float eta = 1.f;   ///< η_t / η_i of a refraction (1 for reflection): lets Russian roulette undo the 1/η² radiance scaling
};

/// GGX α below which a microfacet lobe is treated as its smooth limit, a delta lobe (mirror
/// reflection, refraction). Rough lobes are evaluated with α ≥ kMinAlpha.
inline constexpr float kMinAlpha = 1e-3f;

/// Sets `p.type` from the factors (metallic, alpha, transmission, specular, ior, thinWalled) of a
/// surface point: called by the scene loader for each material and again after textures change the
/// factors. The single-lobe types are the exact special cases of the glTF model (MaterialType::Pbr)
/// and keep their own, cheaper code:
///  * Diffuse: metallic 0, transmission 0, specular 0 (KHR_materials_specular's pure Lambertian);
///  * Mirror / RoughConductor: metallic 1 (α < kMinAlpha / α ≥ kMinAlpha);
///  * Dielectric: smooth glass, a closed volume (not thin-walled), metallic 0, transmission 1,
///    specular 1, specularColor 1;
///  * Pbr: everything else (materials/gltf_pbr.h).
void finalizeBsdfParams(BsdfParams& p);

bool pbrHasNonDeltaLobe(const BsdfParams& m);  // materials/gltf_pbr.h

/// True when every lobe of the material is a delta lobe (eval and pdf are zero everywhere): light
/// sampling is pointless there. A material that mixes a delta lobe with a non-delta one (smooth
/// plastic: delta coat over a diffuse base) is not delta; its samples say which lobe they took
/// (BsdfSample::isDelta), and eval/pdf cover the non-delta lobes only. Inline: every SurfaceBsdf
/// asks once (several per bidirectional connection).
inline bool isDeltaMaterial(const BsdfParams& m) {
    switch (m.type) {
    case MaterialType::Mirror:
    case MaterialType::Dielectric: return true;
    case MaterialType::Pbr: return !pbrHasNonDeltaLobe(m);
    case MaterialType::Diffuse:
    case MaterialType::RoughConductor: return false;
    }
    return false;
}

/// The Lambertian lobe (MaterialType::Diffuse) from the cosines of wo and wi with the shading
/// normal, all it depends on: callers that have them skip the change of frame. Two-sided like
/// every BSDF here (it reflects into wo's hemisphere); evalBsdf and pdfBsdfW use the same two.
inline Rgb lambertEval(const Rgb& albedo, float cosO, float cosI) {
    if (cosO == 0.f) return Rgb(0.f);
    return cosI * (cosO < 0.f ? -1.f : 1.f) > 0.f ? albedo * kInvPi : Rgb(0.f);
}
inline float lambertPdfW(float cosO, float cosI) {
    if (cosO == 0.f) return 0.f;
    return cosineHemispherePdfW(cosI * (cosO < 0.f ? -1.f : 1.f));
}

/// f(wo, wi) without the cosine factor, non-delta lobes only. For refraction `mode` chooses between
/// the BSDF (radiance: the 1/η² compression) and its adjoint (importance), Veach 1997, §5.2.
Rgb evalBsdf(const BsdfParams& m, const Vec3f& woLocal, const Vec3f& wiLocal, TransportMode mode);
/// Solid-angle density with which sampleBsdf generates wi given wo through its non-delta lobes (the
/// lobe-selection probabilities included).
float pdfBsdfW(const BsdfParams& m, const Vec3f& woLocal, const Vec3f& wiLocal);
/// evalBsdf and pdfBsdfW together (one evaluation of the lobes for the glTF model).
Rgb evalBsdfWithPdf(const BsdfParams& m, const Vec3f& woLocal, const Vec3f& wiLocal, TransportMode mode, float& pdfW);
/// Samples wi given wo; `uLobe` picks reflection/refraction, `u` the direction. False when no
/// direction is produced (e.g. wo grazing).
bool sampleBsdf(const BsdfParams& m, const Vec3f& woLocal, float uLobe, Vec2f u, TransportMode mode, BsdfSample& out);
/// Whether sampleBsdf reads `uLobe` (a choice between lobes: dielectric reflection or refraction,
/// the glTF model's lobes) and `u` (a direction within a non-delta lobe) for this material: a
/// smooth mirror reads neither, a Lambertian surface only `u`. Kept next to sampleBsdf: a material
/// type that starts reading a number must say so here (test_gltf_bsdf checks each type).
inline bool sampleBsdfReadsLobeChoice(const BsdfParams& m) { return m.type == MaterialType::Dielectric || m.type == MaterialType::Pbr; }
inline bool sampleBsdfReadsDirection(const BsdfParams& m) { return m.type != MaterialType::Mirror && m.type != MaterialType::Dielectric; }

/// Unpolarised Fresnel reflectance of a dielectric interface; eta = η_inside / η_outside, cosThetaI
/// signed (negative: arriving from inside). Exact formula (Born & Wolf; pbrt-v4 eq. 9.5 form).
float fresnelDielectric(float cosThetaI, float eta);

namespace ggx {
/// Trowbridge–Reitz / GGX normal distribution (Walter et al. 2007, eq. 33).
float D(const Vec3f& wm, float alpha);
/// Smith Λ for GGX (Heitz 2014, "Understanding the Masking-Shadowing Function", eq. 72).
float lambda(const Vec3f& w, float alpha);
/// Visible-normal sampling (Heitz 2018, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4)).
Vec3f sampleVisibleNormal(const Vec3f& wo, float alpha, Vec2f u);
}  // namespace ggx

}  // namespace tessera
