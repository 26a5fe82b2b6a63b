#pragma once
/// \file gltf_pbr.h
/// The glTF 2.0 metallic-roughness material (glTF 2.0 specification, Appendix B) with
/// KHR_materials_specular, KHR_materials_ior, KHR_materials_transmission and the thin-walled /
/// volume distinction of KHR_materials_volume, as one BSDF of up to four lobes:
///
///   f = m · f_metal + (1 − m) · [ f_coat + f_diffuse + f_btdf ]
///   f_metal   = F_Schlick(baseColor, |wo·h|) · D G₂ / (4 |cos θo| |cos θi|)
///   f_coat    = F_d(|wo·h|) · D G₂ / (4 |cos θo| |cos θi|)            (GGX, Walter et al. 2007)
///   f_diffuse = (1 − t) · baseColor/π · (1 − max F_d(cos θo)) (1 − max F_d(cos θi)) / (1 − F_avg)
///   f_btdf    = t · baseColor · (1 − max F_d(|wo·h|)) · Walter's GGX BTDF without its Fresnel
///
/// m = metallic, t = transmission, α = roughness², D = GGX, G₂ = height-correlated Smith
/// (Heitz 2014). F_d is the dielectric Fresnel of KHR_materials_specular:
///   F_d = s · (F0' + (1 − F0') · w),  F0' = min(F0(ior) · specularColor, 1),
/// with w = (F(cos) − F0)/(1 − F0) the angular shape of the exact Fresnel equations (the spec
/// writes Schlick's (1 − cos)⁵ here; Appendix B.3.6.2 encourages the exact equations for
/// dielectrics, which refraction needs for total internal reflection). With s = 1 and
/// specularColor 1, F_d is exactly the Fresnel reflectance.
/// The diffuse base is weighted by what the coat transmits at both ends, normalized by the coat's
/// hemispherical average reflectance F_avg:
///   (1 − max F_d(θo)) (1 − max F_d(θi)) / (1 − F_avg)
/// (Appendix B.3.6.3 names the product, after Burley 2012; the normalization is Kelemen and
/// Szirmay-Kalos 2001's coupling). Reciprocal, and for a smooth coat over a white base exactly
/// energy preserving: albedo F(θo) + (1 − F(θo)) = 1; the spec's (1 − F(wo·h)) mix is neither. Thin-walled transmission leaves on the other side without bending:
/// the reflection lobe mirrored through the surface (straight through when smooth).
/// Below kMinAlpha the coat, metal and BTDF are delta lobes. Lobe choice: writeup.md, "Material model".
#include "materials/bsdf.h"

namespace tessera {

Rgb evalPbr(const BsdfParams& m, const Vec3f& woLocal, const Vec3f& wiLocal, TransportMode mode);
float pdfPbr(const BsdfParams& m, const Vec3f& woLocal, const Vec3f& wiLocal);
/// evalPbr and pdfPbr from one evaluation of the lobes.
Rgb evalPdfPbr(const BsdfParams& m, const Vec3f& woLocal, const Vec3f& wiLocal, TransportMode mode, float& pdfW);
bool samplePbr(const BsdfParams& m, const Vec3f& woLocal, float uLobe, Vec2f u, TransportMode mode, BsdfSample& out);
/// True when the material has a non-delta lobe (a diffuse base, or α ≥ kMinAlpha).
bool pbrHasNonDeltaLobe(const BsdfParams& m);
/// ∫ max F_d(cos θ) 2 cos θ d(cos θ) seen from outside: BsdfParams::coatFresnelAvg.
float pbrCoatFresnelAverage(const BsdfParams& m);

}  // namespace tessera
