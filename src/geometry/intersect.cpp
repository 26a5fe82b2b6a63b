#include "geometry/intersect.h"

namespace tessera {

bool intersectTriangle(const Ray& ray, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, TriangleHit& hit) {
    // Dimension where the ray direction is maximal becomes z; keep the winding by swapping x and y
    // when d[kz] is negative (paper, Section 3.1).
    Vec3f ad = glm::abs(ray.d);
    int kz = ad.x > ad.y ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
    if (ray.d[kz] == 0.f) return false;
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (ray.d[kz] < 0.f) std::swap(kx, ky);
    float sx = ray.d[kx] / ray.d[kz], sy = ray.d[ky] / ray.d[kz], sz = 1.f / ray.d[kz];

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
