#pragma once
/// \file volume.h
/// Beer–Lambert absorption inside KHR_materials_volume bodies: the one home of the rule that says
/// whether a path segment runs inside a volume, and of its transmittance T = exp(−σa·length).
///
/// The rule. A glTF volume is a closed mesh with outward normals whose material is not thin-walled
/// (thicknessFactor > 0); its σa = −ln(attenuationColor)/attenuationDistance is in BsdfParams. A
/// segment between two path vertices lies inside such a body when it leaves one of its ends on the
/// back side of that end's geometric normal and that end's material is an attenuating volume. Each
/// end is tested looking along the segment away from itself (volumeSigmaAt), so the leaving end of
/// a traced ray and the arriving end (tested with wo, the direction back to the ray's origin) are the
/// same test: a segment gets the same σa whichever end a strategy starts from. Where both ends
/// qualify with different σa (touching or nested bodies, which are not modelled) the componentwise
/// maximum keeps the rule symmetric.
///
/// Why symmetry matters: BDPT builds one path by several strategies (camera walk, light walk,
/// connection edge, NEE shadow segment, lens connection). The transmittance is part of the path's
/// contribution f, not of its sampling densities, so the MIS weights (which depend only on the
/// densities) still sum to one over the strategies, and the combination stays unbiased exactly when
/// every strategy multiplies the same f: each must evaluate the same T for the same segment
/// (Veach 1997, §9.2.2: unbiased for any weights that partition unity, given a common integrand).
///
/// A point sampled on an area light is tested with its emitter's material like any surface end
/// (emitterVolumeSigma). Ends that are not surfaces (the lens, point/spot lights, a vertex at
/// infinity) never qualify, but the other end can: a camera or light inside a body is attenuated up to the first surface, whose
/// inside (back side) it reaches. A segment that runs inside a body towards infinity (an escaped ray
/// or a shadow ray to an infinite light) has infinite length: its attenuating channels are 0 (a
/// closed body would have been hit from the inside). Not modelled: nested volumes (one σa per
/// segment, no medium stack), scattering media (absorption only), σa varying inside the body.
#include <cmath>
#include <limits>

#include "core/math.h"
#include "materials/material.h"
#include "scene/scene.h"

namespace tessera {

/// σa of the segment as seen from one of its surface ends: `bsdf` and `ng` at that end, `wAway` the
/// direction along the segment away from the end (the spawned ray's direction where the segment
/// leaves it; wo where the segment arrives). Zero unless the segment lies on the back side of `ng`
/// and the material is a non-thin-walled volume with non-zero σa.
inline Rgb volumeSigmaAt(const BsdfParams& bsdf, const Vec3f& ng, const Vec3f& wAway) {
    if (bsdf.thinWalled || isBlack(bsdf.attenuationCoeff) || !(glm::dot(wAway, ng) < 0.f)) return Rgb(0.f);
    return bsdf.attenuationCoeff;
}

/// volumeSigmaAt for a segment end that is a point sampled on an area light (a light sub-path's
/// origin, a next-event sample): the emitter's own material decides, as it does when a traced ray
/// hits that emitter. `n` is the light sample's surface normal (the geometric normal; zero for
/// point, spot and infinite lights, which are never volume boundaries). KHR_materials_volume's σa
/// and thickness are untextured factors, so the material's own BsdfParams are exact.
inline Rgb emitterVolumeSigma(const Scene& scene, uint32_t lightIndex, const Vec3f& n, const Vec3f& wAway) {
    if (lightIndex == kInvalidId || n == Vec3f(0.f)) return Rgb(0.f);
    const Light& l = scene.lights().light(lightIndex);
    uint32_t material = kInvalidId;
    if (l.type == LightType::Triangle) material = scene.geometry.meshes[l.geomId].materialId;
    else if (l.type == LightType::Sphere) material = scene.geometry.spheres[l.primId].materialId;
    if (material == kInvalidId) return Rgb(0.f);
    return volumeSigmaAt(scene.materials[material].bsdf, n, wAway);
}

/// True when a segment with these end σa (volumeSigmaAt of each end; zero for non-surface ends)
/// is attenuated at all: callers multiply nothing otherwise, so scenes without volumes keep their bits.
inline bool segmentAttenuates(const Rgb& sigmaA, const Rgb& sigmaB) { return !isBlack(sigmaA) || !isBlack(sigmaB); }

/// Beer–Lambert transmittance exp(−σ·length) of a segment with end σa `sigmaA`, `sigmaB` (either
/// order: the result is symmetric). `length` may be infinite (a segment towards infinity): the
/// channels with σ > 0 are then 0, the others 1.
inline Rgb segmentTransmittance(const Rgb& sigmaA, const Rgb& sigmaB, float length) {
    Rgb sigma = glm::max(sigmaA, sigmaB);
    Rgb T(1.f);
    for (int c = 0; c < 3; ++c)
        if (sigma[c] > 0.f) T[c] = std::isinf(length) ? 0.f : std::exp(-sigma[c] * length);
    return T;
}

/// The length to pass for a segment one of whose ends lies at infinity.
inline constexpr float kInfiniteSegment = std::numeric_limits<float>::infinity();

// The two places a camera path's segment ends (pt, ptnee, sppm), with the rule above:
/// a ray that leaves the scene from a surface whose side it left has σa `sigmaLeave`: β loses the
/// channels that side absorbs (an infinite segment);
inline void attenuateEscape(Rgb& beta, const Rgb& sigmaLeave) {
    if (!isBlack(sigmaLeave)) beta *= segmentTransmittance(sigmaLeave, Rgb(0.f), kInfiniteSegment);
}
/// a ray from `prevP` that arrives at a surface (its material `params`, normal ng, seen from wo):
/// β times the segment's transmittance, untouched when neither end absorbs.
inline void attenuateArrival(Rgb& beta, const Rgb& sigmaLeave, const BsdfParams& params, const Vec3f& ng, const Vec3f& wo,
                             const Vec3f& p, const Vec3f& prevP) {
    if (Rgb sigmaArrive = volumeSigmaAt(params, ng, wo); segmentAttenuates(sigmaLeave, sigmaArrive))
        beta *= segmentTransmittance(sigmaLeave, sigmaArrive, glm::length(p - prevP));
}

}  // namespace tessera
