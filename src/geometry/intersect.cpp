#include "geometry/intersect.h"

namespace tessera {

bool intersectTriangle(const Ray& ray, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, TriangleHit& hit) {
    // Woop et al. 2013; the axes as in the SIMD leaf tests (watertightAxes).
    const float d[3] = {ray.d.x, ray.d.y, ray.d.z};
    const auto [kx, ky, kz] = watertightAxes(d);
    if (d[kz] == 0.f) return false;
    float sx = d[kx] / d[kz], sy = d[ky] / d[kz], sz = 1.f / d[kz];

    Vec3f a = p0 - ray.o, b = p1 - ray.o, c = p2 - ray.o;
    float ax = a[kx] - sx * a[kz], ay = a[ky] - sy * a[kz];
    float bx = b[kx] - sx * b[kz], by = b[ky] - sy * b[kz];
    float cx = c[kx] - sx * c[kz], cy = c[ky] - sy * c[kz];
    float U = cx * by - cy * bx;
    float V = ax * cy - ay * cx;
    float W = bx * ay - by * ax;
    if (U == 0.f || V == 0.f || W == 0.f) {
        U = float(double(cx) * double(by) - double(cy) * double(bx));
        V = float(double(ax) * double(cy) - double(ay) * double(cx));
        W = float(double(bx) * double(ay) - double(by) * double(ax));
    }
    if ((U < 0.f || V < 0.f || W < 0.f) && (U > 0.f || V > 0.f || W > 0.f)) return false;
    float det = U + V + W;
    if (det == 0.f) return false;
    float az = sz * a[kz], bz = sz * b[kz], cz = sz * c[kz];
    float T = U * az + V * bz + W * cz;
    float invDet = 1.f / det;
    float t = T * invDet;
    if (!(t > ray.tMin && t < ray.tMax)) return false;
    hit.t = t;
    // U weighs p0, V weighs p1, W weighs p2.
    hit.u = V * invDet;
    hit.v = W * invDet;
    return true;
}

}  // namespace tessera
