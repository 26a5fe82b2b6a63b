#include "geometry/clip.h"

#include <algorithm>
#include <cmath>

namespace tessera {

namespace {

float roundDown(double x) {
    float f = float(x);
    return double(f) > x ? std::nextafter(f, -kInfinity) : f;
}
float roundUp(double x) {
    float f = float(x);
    return double(f) < x ? std::nextafter(f, kInfinity) : f;
}

/// Sutherland–Hodgman clip of a convex polygon against one axis-aligned half-space
/// (keep x[axis] ≥ v when `keepAbove`, else x[axis] ≤ v). Returns the new vertex count.
int clipPolygon(const Vec3d* in, int n, Vec3d* out, int axis, double v, bool keepAbove) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const Vec3d& a = in[i];
        const Vec3d& b = in[(i + 1) % n];
        double da = keepAbove ? a[axis] - v : v - a[axis];
        double db = keepAbove ? b[axis] - v : v - b[axis];
        if (da >= 0.0) out[m++] = a;
        if ((da >= 0.0) != (db >= 0.0) && da != db) {
            double t = da / (da - db);
            Vec3d p = a + t * (b - a);
            p[axis] = v;  // exactly on the plane, whatever the rounding of t
            out[m++] = p;
        }
    }
    return m;
}

}  // namespace

/// Exact-as-double clip of the triangle to the box; false when nothing remains.
bool clipTriangleDouble(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box, Vec3d& lo, Vec3d& hi) {
    Vec3d bufA[12], bufB[12];
    bufA[0] = Vec3d(p0), bufA[1] = Vec3d(p1), bufA[2] = Vec3d(p2);
    int n = 3;
    Vec3d* cur = bufA;
    Vec3d* nxt = bufB;
    // Cheap pre-pass: planes the triangle lies entirely on the kept side of need no clipping.
    Vec3f tlo = glm::min(p0, glm::min(p1, p2)), thi = glm::max(p0, glm::max(p1, p2));
    for (int a = 0; a < 3 && n > 0; ++a) {
        if (tlo[a] < box.lower[a]) {
            n = clipPolygon(cur, n, nxt, a, double(box.lower[a]), true);
            std::swap(cur, nxt);
        }
        if (n > 0 && thi[a] > box.upper[a]) {
            n = clipPolygon(cur, n, nxt, a, double(box.upper[a]), false);
            std::swap(cur, nxt);
        }
    }
    if (n == 0) return false;
    lo = hi = cur[0];
    for (int i = 1; i < n; ++i) lo = glm::min(lo, cur[i]), hi = glm::max(hi, cur[i]);
    return true;
}

Bounds3f clipTriangleBounds(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box) {
    Vec3d lo, hi;
    Bounds3f b;
    if (!clipTriangleDouble(p0, p1, p2, box, lo, hi)) return b;
    for (int a = 0; a < 3; ++a) {
        b.lower[a] = std::max(roundDown(lo[a]), box.lower[a]);
        b.upper[a] = std::min(roundUp(hi[a]), box.upper[a]);
    }
    return b;
}

}  // namespace tessera
