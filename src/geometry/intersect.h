#pragma once
/// \file intersect.h
/// Reference ray–primitive tests shared by the brute-force backend, the Embree sphere callback and
/// the mixed (sphere-holding) leaves of our BVH and k-d tree.
#include "core/math.h"
#include "core/ray.h"

namespace tessera {

/// The watertight triangle test's axes (Woop, Benthin & Wald 2013, "Watertight Ray/Triangle
/// Intersection", JCGT 2(1), Section 3.1): kz the direction's dominant axis (x if |dx| > |dy| and
/// |dx| > |dz|, else y if |dy| > |dz|, else z), kx and ky the next two, swapped when d[kz] < 0 to
/// keep the winding. By arithmetic, not branches: for incoherent rays the dominant axis and its sign
/// are coin tosses, and conditionals here compiled to branches that mispredicted about once per ray
/// (docs/perf-log.md, "Mispredicted per-ray set-up branches").
struct WatertightAxes {
    int kx, ky, kz;
};
inline WatertightAxes watertightAxes(const float (&d)[3]) {
    float ax = std::abs(d[0]), ay = std::abs(d[1]), az = std::abs(d[2]);
    int xOverY = ax > ay, kzIfX = 2 * int(!(ax > az)), kzIfNotX = 2 - int(ay > az);
    int kz = kzIfNotX + (kzIfX - kzIfNotX) * xOverY;
    static constexpr int kNext[3] = {1, 2, 0};
    int x = kNext[kz], y = kNext[x], negative = d[kz] < 0.f;
    return {x + (y - x) * negative, y + (x - y) * negative, kz};
}

/// Both distances t0 ≤ t1 at which the line o + t·d meets the sphere |x − c| = r, in double
/// precision, using the discriminant form of Haines et al. 2019 ("Precision Improvements for
/// Ray/Sphere Intersection", Ray Tracing Gems ch. 7, eq. 7.10 and the stable quadratic of eq. 7.11):
/// r² − |f − (f·d̂)d̂|² instead of b² − 4ac, which loses every digit when |f| ≫ r or r ≫ t (our walls
/// are spheres of radius 1e4 seen from 1e2 away). False when the line misses the sphere.
inline bool sphereRoots(const Vec3d& o, const Vec3d& d, const Vec3d& c, double r, double& t0, double& t1) {
    double dd = glm::dot(d, d);
    if (!(dd > 0.0)) return false;
    Vec3d f = o - c;
    double b = -glm::dot(f, d);                   // = −b/2 in a t² + b t + c (unnormalised d)
    Vec3d l = f + (b / dd) * d;                   // f minus its projection on d
    double disc = dd * (r * r - glm::dot(l, l));  // = (b/2)² − a c, computed without cancellation
    if (disc < 0.0) return false;
    double cq = glm::dot(f, f) - r * r;
    double q = b + std::copysign(std::sqrt(disc), b);
    t0 = (q != 0.0) ? cq / q : 0.0;
    t1 = q / dd;
    if (t0 > t1) std::swap(t0, t1);
    return true;
}

/// Ray–sphere intersection in double precision (sphereRoots). Returns the nearest t in
/// (ray.tMin, ray.tMax), or a negative value when there is none.
inline double intersectSphere(const Vec3f& centerF, float radiusF, const Ray& ray) {
    double t0, t1;
    if (!sphereRoots(Vec3d(ray.o), Vec3d(ray.d), Vec3d(centerF), double(radiusF), t0, t1)) return -1.0;
    if (t0 > ray.tMin && t0 < ray.tMax) return t0;
    if (t1 > ray.tMin && t1 < ray.tMax) return t1;
    return -1.0;
}

/// Unit outward normal of a sphere hit at the distance `t` a hit record reports (already rounded to
/// float), in double precision. One expression for every backend (brute force, the Embree
/// callback, the BVH's and k-d tree's sphere leaves), so their records agree bit for bit.
inline Vec3f sphereHitNormal(const Vec3f& center, const Ray& ray, float t) {
    return glm::normalize(Vec3f(Vec3d(ray.o) + double(t) * Vec3d(ray.d) - Vec3d(center)));
}

/// Spherical (u, v) = (φ/2π, θ/π) of a unit direction from the sphere's centre; θ from +y.
inline Vec2f sphereUv(const Vec3f& nUnit) {
    float phi = std::atan2(nUnit.z, nUnit.x);
    if (phi < 0.f) phi += 2.f * kPi;
    float theta = std::acos(std::clamp(nUnit.y, -1.f, 1.f));
    return {phi * kInv2Pi, theta * kInvPi};
}

/// Hit point on a sphere reprojected onto its surface in double precision: o + t·d carries the error
/// of t times |d|; the projection leaves only the final rounding to float.
inline Vec3f sphereSurfacePoint(const Vec3f& center, float radius, const Vec3f& approxPoint) {
    Vec3d c(center), p(approxPoint);
    Vec3d dir = p - c;
    double len = glm::length(dir);
    if (!(len > 0.0)) return approxPoint;
    return Vec3f(c + dir * (double(radius) / len));
}

struct TriangleHit {
    float t, u, v;  ///< u, v: barycentrics of p1 and p2 (Embree's convention)
};

/// Watertight ray–triangle test (Woop, Benthin & Wald 2013, "Watertight Ray/Triangle Intersection",
/// JCGT 2(1)): shear into ray space so that edge functions of neighbouring triangles agree bit for bit;
/// falls back to double precision when an edge function is exactly zero (Section 3.3).
bool intersectTriangle(const Ray& ray, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, TriangleHit& hit);

}  // namespace tessera
