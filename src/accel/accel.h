#pragma once
/// \file accel.h
/// The one interface every ray-tracing backend implements (Embree, our BVH with and without spatial
/// splits, our k-d tree, brute force). Chosen at run time with `--accel NAME`. Integrators only ever
/// see this interface.
/// Cut-outs: a hit on a triangle of a mesh with an alpha mask (glTF alphaMode MASK) counts only where
/// alphaMaskKeeps (geometry/alpha_mask.h) keeps it, for every query, in every backend: a dropped hit
/// is as if the triangle were not there, so the next one behind it is found.
#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/bounds.h"
#include "core/ray.h"
#include "geometry/hit.h"
#include "geometry/shapes.h"

namespace tessera {

struct AccelStats {
    double buildSeconds = 0.0;
    size_t memoryBytes = 0;  ///< of the structure itself, excluding the scene's vertex data
    size_t primitives = 0;
};

struct AccelOptions {
    /// Threads for the builds that run in parallel (0 = all): Embree's device, our BVH's
    /// object-split build and the k-d tree build. The spatial-split build is serial.
    int threads = 0;
};

class Accel {
public:
    virtual ~Accel() = default;
    virtual std::string_view name() const = 0;
    /// Closest hit with t in (ray.tMin, ray.tMax). Rays with a non-finite origin or direction, or a
    /// zero direction, never hit. Thread-safe.
    virtual bool intersect(const Ray& ray, Hit& hit) const = 0;
    /// intersect() for a ray that closely follows the previous one this thread traced (camera rays
    /// in pixel order): the same record, bit for bit, but a backend may run a kernel whose branches
    /// pay off only when they predict well. Our BVH branches on the number of hit children for
    /// such rays and orders them branch-free for all others; Embree gets
    /// RTC_INTERSECT_CONTEXT_FLAG_COHERENT. Thread-safe.
    virtual bool intersectCoherent(const Ray& ray, Hit& hit) const { return intersect(ray, hit); }
    /// Any hit with t in (ray.tMin, ray.tMax) (shadow rays). Thread-safe.
    virtual bool occluded(const Ray& ray) const = 0;
    virtual Bounds3f bounds() const = 0;
    virtual AccelStats stats() const = 0;
};

/// Names accepted by createAccel, e.g. {"embree", "brute"}.
std::vector<std::string> accelNames();

/// Builds the named backend over `geometry`, which must outlive it. Throws InputError on an
/// unknown name.
std::unique_ptr<Accel> createAccel(std::string_view name, const SceneGeometry& geometry,
                                   const AccelOptions& options = {});

/// True when the ray can be traced at all (finite origin and direction, non-zero direction, tMin ≤ tMax).
/// Branch-light: x·0 is 0 for finite x and NaN for ±inf and NaN. This runs once per ray in every
/// traversal kernel: with SSE the ray's 8 floats are two vectors and the tests four compares and
/// four mask extractions, where the scalar form (the fallback) chains six products and five sums.
inline bool isTraceableRay(const Ray& r) {
#if defined(__SSE2__)
    static_assert(sizeof(Ray) == 8 * sizeof(float) && offsetof(Ray, d) == 12 && offsetof(Ray, tMin) == 24);
    const float* f = reinterpret_cast<const float*>(&r);
    const __m128 a = _mm_loadu_ps(f), b = _mm_loadu_ps(f + 4), zero = _mm_setzero_ps();  // [ox oy oz dx], [dy dz tMin tMax]
    const int finiteA = _mm_movemask_ps(_mm_cmpeq_ps(_mm_mul_ps(a, zero), zero));
    const int finiteB = _mm_movemask_ps(_mm_cmpeq_ps(_mm_mul_ps(b, zero), zero)) | 0xC;  // tMin, tMax may be infinite
    const int nonZeroDirection = (_mm_movemask_ps(_mm_cmpneq_ps(a, zero)) & 0x8) | (_mm_movemask_ps(_mm_cmpneq_ps(b, zero)) & 0x3);
    return ((finiteA & finiteB) == 0xF) & (nonZeroDirection != 0) & (r.tMin <= r.tMax);  // false for a NaN tMin or tMax too
#else
    float zero = r.o.x * 0.f + r.o.y * 0.f + r.o.z * 0.f + r.d.x * 0.f + r.d.y * 0.f + r.d.z * 0.f;
    bool nonZeroDirection = (r.d.x != 0.f) | (r.d.y != 0.f) | (r.d.z != 0.f);
    return (zero == 0.f) & nonZeroDirection & (r.tMin <= r.tMax);
#endif
}

}  // namespace tessera
