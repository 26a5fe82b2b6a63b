#pragma once
/// \file next_event.h
/// Next-event estimation (NEE): from a surface vertex, sample one point on a light and connect to it
/// with a shadow ray (Veach 1997, §9.1.2 "light sampling"). Written once for `ptnee` (at every
/// path vertex) and BDPT's s = 1 strategy (Veach 1997, §10.2), which therefore draw the same random
/// numbers in the same order: uPick (1D, which light) then uLight (2D, where on it).
/// The callers weight the sample differently (ptnee against BSDF sampling of the same vertex,
/// BDPT against every (s, t) strategy of the path), so the weights stay with them.
#include "accel/accel.h"
#include "core/sampler.h"
#include "scene/lights.h"

namespace tessera {

struct NextEventSample {
    LightSample light;
    /// The point the light was sampled from: the vertex offset off its surface on wo's side.
    Vec3f pRef{0.f};
};

/// Samples a light point as seen from the surface point `p` (geometric normal `ng`, `woWorld` the
/// unit direction towards the previous path vertex). The light is sampled from the point offset off
/// the surface on wo's side (where reflected rays start), not from `p` itself: for a point on an
/// emitting sphere, "inside or outside the sphere" must not be decided by rounding.
/// Draws no random numbers when the scene has no lights. False when there are none, or the sample
/// carries no radiance.
bool sampleNextEvent(const LightSet& lights, const Vec3f& p, const Vec3f& ng, const Vec3f& woWorld, Sampler& sampler,
                     NextEventSample& out);

/// True when nothing blocks the segment between the surface point (p, ng) and the sampled light
/// point (both ends offset off their surfaces), or, for an infinite light, the ray towards it.
inline bool lightVisible(const Accel& accel, const Vec3f& p, const Vec3f& ng, const LightSample& light) {
    if (light.isInfinite) return !accel.occluded(spawnRay(p, ng, light.wi));
    return !accel.occluded(spawnShadowRay(p, ng, light.p, light.n));
}

}  // namespace tessera
