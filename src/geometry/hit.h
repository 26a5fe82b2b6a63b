#pragma once
/// \file hit.h
/// The closest-hit record every ray-tracing backend returns (accel/accel.h) and the scene turns
/// into a surface interaction (scene/scene.h).
#include <cstdint>

#include "core/math.h"
#include "geometry/shapes.h"

namespace tessera {

/// What a closest-hit query returns. The same record for every backend, so they can be compared
/// ray by ray: t along the (unnormalised) ray direction; (u, v) barycentrics of vertices 1 and 2 for
/// triangles (Embree's convention) or spherical (φ/2π, θ/π) for spheres; ids as in SceneGeometry;
/// `ng` the unit geometric normal (triangles: normalize((p1−p0)×(p2−p0)); spheres: outward), in
/// world space. A hit on an instance (SceneGeometry::instances) has instId = its index and
/// geomId/primId/u/v of the prototype's mesh and triangle; its ng is the object-space normal taken
/// to world space by the inverse transpose (instanceNormalToWorld); instId is kInvalidId otherwise.
struct Hit {
    float t = kInfinity;
    float u = 0.f, v = 0.f;
    uint32_t primId = kInvalidId;
    uint32_t geomId = kInvalidId;
    uint32_t instId = kInvalidId;
    Vec3f ng{0.f};
};

}  // namespace tessera
