#pragma once
/// \file bsdf_local.h
/// Small helpers of the BSDF code in the local shading frame (z = shading normal), shared by
/// bsdf.cpp (the single-lobe BSDFs) and gltf_pbr.cpp (the glTF metallic-roughness mixture).
/// Internal to src/materials.
#include "core/math.h"

namespace tessera::bsdf_local {

inline float cos2Theta(const Vec3f& w) { return w.z * w.z; }
inline float sin2Theta(const Vec3f& w) { return std::max(0.f, 1.f - cos2Theta(w)); }
inline float tan2Theta(const Vec3f& w) { return sin2Theta(w) / cos2Theta(w); }
inline Vec3f reflectLocal(const Vec3f& w) { return {-w.x, -w.y, w.z}; }
/// The mirror image of `w` through the tangent plane (thin-walled transmission).
inline Vec3f flipZ(const Vec3f& w) { return {w.x, w.y, -w.z}; }
inline float average(const Rgb& c) { return (c.r + c.g + c.b) * (1.f / 3.f); }

/// Schlick's approximation with a coloured F0 (Schlick 1994), as glTF's metal model prescribes.
inline Rgb fresnelSchlick(const Rgb& f0, float cosTheta) {
    float m = std::clamp(1.f - cosTheta, 0.f, 1.f);
    float m2 = m * m;
    return f0 + (Rgb(1.f) - f0) * (m2 * m2 * m);
}

/// Refracts `wi` about the +z normal (wi and the normal on the same side); eta = η_t / η_i.
inline bool refractLocal(const Vec3f& wi, float eta, Vec3f& wt) {
    float cosI = wi.z;
    float sin2T = sin2Theta(wi) / (eta * eta);
    if (sin2T >= 1.f) return false;
    float cosT = std::sqrt(1.f - sin2T);
    wt = -wi / eta + Vec3f(0.f, 0.f, cosI / eta - cosT);
    return true;
}

/// Refracts `wi` about the unit normal `n` with wi·n > 0 (a microfacet normal); eta = η_t / η_i.
/// False on total internal reflection.
inline bool refractAbout(const Vec3f& wi, const Vec3f& n, float eta, Vec3f& wt) {
    float cosI = glm::dot(wi, n);
    float sin2T = std::max(0.f, 1.f - cosI * cosI) / (eta * eta);
    if (sin2T >= 1.f) return false;
    float cosT = std::sqrt(1.f - sin2T);
    wt = -wi / eta + (cosI / eta - cosT) * n;
    return true;
}

}  // namespace tessera::bsdf_local
