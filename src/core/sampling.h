#pragma once
/// \file sampling.h
/// Warps from the unit square to the domains Tessera samples, each with its density.
#include "core/math.h"

namespace tessera {

/// Concentric map square → unit disk (Shirley & Chiu 1997, "A Low Distortion Map Between Disk and
/// Square"): keeps stratification, unlike the polar map.
inline Vec2f sampleConcentricDisk(Vec2f u) {
    Vec2f o = 2.f * u - Vec2f(1.f);
    if (o.x == 0.f && o.y == 0.f) return Vec2f(0.f);
    float r, theta;
    if (std::abs(o.x) > std::abs(o.y)) {
        r = o.x;
        theta = 0.25f * kPi * (o.y / o.x);
    } else {
        r = o.y;
        theta = 0.5f * kPi - 0.25f * kPi * (o.x / o.y);
    }
    return r * Vec2f(std::cos(theta), std::sin(theta));
}

/// Cosine-weighted hemisphere around +z (Malley's method): pdfW = cos θ / π.
inline Vec3f sampleCosineHemisphere(Vec2f u) {
    Vec2f d = sampleConcentricDisk(u);
    float z = safeSqrt(1.f - d.x * d.x - d.y * d.y);
    return {d.x, d.y, z};
}
inline float cosineHemispherePdfW(float cosTheta) { return cosTheta > 0.f ? cosTheta * kInvPi : 0.f; }

/// Uniform direction on the unit sphere: pdfW = 1 / 4π.
inline Vec3f sampleUniformSphere(Vec2f u) {
    float z = 1.f - 2.f * u.x;
    float r = safeSqrt(1.f - z * z);
    float phi = 2.f * kPi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
inline constexpr float kUniformSpherePdfW = 1.f / (4.f * kPi);

/// Uniform point on a triangle as barycentrics (b0, b1); b2 = 1 − b0 − b1 (Heitz 2019, "A
/// Low-Distortion Map Between Triangle and Square"): pdfA = 1 / area.
inline Vec2f sampleUniformTriangle(Vec2f u) {
    float b0, b1;
    if (u.x < u.y) {
        b0 = u.x / 2.f;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.f;
        b0 = u.x - b1;
    }
    return {b0, b1};
}

/// Veach's power heuristic with β = 2 (Veach 1997, eq. 9.13) for two strategies, one sample each.
inline float powerHeuristic(float pdfA, float pdfB) {
    if (std::isinf(pdfA)) return 1.f;
    float a = pdfA * pdfA, b = pdfB * pdfB;
    return a + b > 0.f ? a / (a + b) : 0.f;
}

}  // namespace tessera
