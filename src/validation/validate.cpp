#include "validation/validate.h"

#include <tbb/parallel_for.h>

#include <cstring>

#include "geometry/alpha_mask.h"
#include "geometry/intersect.h"

namespace tessera {
namespace {

/// The same record bit for bit (intersectCoherent must return exactly what intersect does).
bool sameRecord(bool hitA, const Hit& a, bool hitB, const Hit& b) {
    if (hitA != hitB) return false;
    if (!hitA) return true;
    auto bits = [](float x) {
        uint32_t u;
        std::memcpy(&u, &x, 4);
        return u;
    };
    return bits(a.t) == bits(b.t) && bits(a.u) == bits(b.u) && bits(a.v) == bits(b.v) && a.primId == b.primId &&
           a.geomId == b.geomId && bits(a.ng.x) == bits(b.ng.x) && bits(a.ng.y) == bits(b.ng.y) && bits(a.ng.z) == bits(b.ng.z);
}

/// Double-precision Möller–Trumbore (1997) without the edge test: t and barycentrics (b1, b2) of the
/// ray's crossing with the triangle's plane. False when the ray is parallel to it.
bool planeHit(const Ray& r, const Vec3d& p0, const Vec3d& p1, const Vec3d& p2, double& t, double& b1, double& b2) {
    Vec3d o(r.o), d(r.d), e1 = p1 - p0, e2 = p2 - p0;
    Vec3d pv = glm::cross(d, e2);
    double det = glm::dot(e1, pv);
    if (det == 0.0) return false;
    Vec3d tv = o - p0;
    b1 = glm::dot(tv, pv) / det;
    Vec3d qv = glm::cross(tv, e1);
    b2 = glm::dot(d, qv) / det;
    t = glm::dot(e2, qv) / det;
    return true;
}

/// Distance between the line o + s·d and the segment [a, b], in double precision.
double lineSegmentDistance(const Vec3d& o, const Vec3d& d, const Vec3d& a, const Vec3d& b, double* rayT = nullptr) {
    Vec3d e = b - a, w0 = a - o;
    double dd = glm::dot(d, d), ee = glm::dot(e, e), de = glm::dot(d, e), dw = glm::dot(d, w0), ew = glm::dot(e, w0);
    double den = dd * ee - de * de;
    double s = den > 1e-300 * dd * ee ? (de * dw - dd * ew) / den : 0.0;  // segment parameter
    s = std::clamp(s, 0.0, 1.0);
    Vec3d q = a + s * e;
    double lineS = glm::dot(q - o, d) / dd;
    if (rayT) *rayT = lineS;
    return glm::length(o + lineS * d - q);
}

/// How much float rounding of a triangle's vertices can move its plane and edges, relative to a
/// well-shaped triangle: longest edge² / (2·area) ≈ 1 / sin(smallest angle). About 1–3 for ordinary
/// triangles, 1e5 for a 10 × 1e-4 sliver, whose plane (and so t) no float test can pin down.
double conditionNumber(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2) {
    double longest = std::max({glm::length(p1 - p0), glm::length(p2 - p1), glm::length(p0 - p2)});
    double area2 = glm::length(glm::cross(p1 - p0, p2 - p0));
    return area2 > 0.0 ? std::max(1.0, longest * longest / area2) : 1e30;
}

/// What double precision says about a primitive along a ray: the t where the ray meets it (or
/// passes closest), and whether that point is within `slack` (world units) of the primitive's
/// boundary, where both a hit and a miss are admissible.
struct PrimCheck {
    bool hitInside = false;  ///< strictly inside, farther than slack from the boundary
    bool nearBoundary = false;
    double t = -1.0;
    double slack = 0.0;
    /// Cut-out triangles (alpha mask): whether the mask keeps the point where the ray meets the
    /// plane, and whether that answer could flip within `slack` of it (a point on the mask's cutoff
    /// contour, or no point at all for a ray parallel to the plane), where keeping and dropping the
    /// hit are both admissible. Opaque primitives: kept, never marginal.
    bool alphaKept = true;
    bool alphaMarginal = false;
};

/// The alpha-mask part of a PrimCheck: the mask evaluated at the double-precision barycentrics
/// (b1, b2) of the ray's crossing with the plane and at the four points around it that float
/// rounding could have reported instead: c.slack (world units) off the plane moves the crossing by
/// slack / cos θ along it, θ the angle between the ray and the normal (as in sameHitRecord).
void checkAlpha(const TriangleMesh& m, uint32_t primId, const Vec3d (&p)[3], const Ray& r, double b1, double b2, PrimCheck& c) {
    auto keeps = [&](double u, double v) { return alphaMaskKeeps(m, primId, float(u), float(v)); };
    c.alphaKept = keeps(b1, b2);
    Vec3d cross = glm::cross(p[1] - p[0], p[2] - p[0]), d(r.d);
    double area2 = glm::length(cross);
    double cosine = area2 > 0.0 ? std::abs(glm::dot(cross, d)) / (area2 * glm::length(d)) : 0.0;
    double band = c.slack / std::max(cosine, 1e-6);
    // Barycentric b1 grows by 1 across the altitude from p1 to the edge p0–p2 (b2 likewise).
    double du = area2 > 0.0 ? band * glm::length(p[2] - p[0]) / area2 : 1.0;
    double dv = area2 > 0.0 ? band * glm::length(p[1] - p[0]) / area2 : 1.0;
    // A crossing that rounding could move by more than a hundredth of the triangle (a ray almost in
    // its plane) has no mask answer to insist on.
    c.alphaMarginal = du > 0.01 || dv > 0.01 || keeps(b1 - du, b2) != c.alphaKept || keeps(b1 + du, b2) != c.alphaKept ||
                      keeps(b1, b2 - dv) != c.alphaKept || keeps(b1, b2 + dv) != c.alphaKept;
}

PrimCheck checkPrimitive(const SceneGeometry& g, const Ray& r, uint32_t geomId, uint32_t primId, float edgeUlps) {
    PrimCheck c;
    Vec3d o(r.o), d(r.d);
    double dLen = glm::length(d);
    if (geomId < g.meshes.size()) {
        const TriangleMesh& m = g.meshes[geomId];
        const glm::uvec3& tri = m.triangles[primId];
        Vec3d p[3] = {Vec3d(m.positions[tri.x]), Vec3d(m.positions[tri.y]), Vec3d(m.positions[tri.z])};
        double scale = glm::length(o);
        for (const Vec3d& q : p) scale = std::max(scale, glm::length(q));
        double t = 0.0, b1 = 0.0, b2 = 0.0;
        bool plane = planeHit(r, p[0], p[1], p[2], t, b1, b2);
        c.t = plane ? t : -1.0;
        c.slack = edgeUlps * 0x1p-24 * (scale + (plane ? std::abs(t) * dLen : 0.0)) * conditionNumber(p[0], p[1], p[2]);
        double edgeDist = kInfinity, edgeT = 0.0;
        for (int e = 0; e < 3; ++e) {
            double rayT;
            double dist = lineSegmentDistance(o, d, p[e], p[(e + 1) % 3], &rayT);
            if (dist < edgeDist) edgeDist = dist, edgeT = rayT;
        }
        c.nearBoundary = edgeDist <= c.slack;
        if (!plane) {
            // Parallel to the plane: only touching an edge counts, at the closest approach.
            if (c.nearBoundary) c.t = edgeT;
            c.alphaMarginal = bool(m.alphaMask);  // no single point to evaluate the mask at
            return c;
        }
        if (m.alphaMask) checkAlpha(m, primId, p, r, b1, b2, c);
        // A ray grazing an edge or vertex is hit there: the plane intersection is ill-conditioned
        // when the ray lies (nearly) in the triangle's plane — an edge-on triangle touched at a
        // vertex it shares with the triangle the reference reports — and would put t anywhere.
        if (c.nearBoundary) c.t = edgeT;
        bool inside = b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0;
        c.hitInside = inside && !c.nearBoundary;
        if (!inside && !c.nearBoundary) c.t = -1.0;
        return c;
    }
    const Sphere& s = g.spheres[primId];
    Vec3d ctr(s.center);
    double proj = glm::dot(ctr - o, d) / (dLen * dLen);
    double dist = glm::length(o + proj * d - ctr);
    double scale = std::max(glm::length(o), glm::length(ctr) + s.radius);
    c.slack = edgeUlps * 0x1p-24 * scale;
    c.nearBoundary = std::abs(dist - double(s.radius)) <= c.slack;
    double t = intersectSphere(s.center, s.radius, r);
    c.t = t >= 0.0 ? t : (c.nearBoundary ? proj : -1.0);
    c.hitInside = t >= 0.0 && !c.nearBoundary;
    return c;
}

double tTolerance(const Ray& r, double t, const ValidationTolerances& tol, double slack) {
    // Relative t, plus the positional slack of the primitive expressed along the ray.
    return tol.tRelative * std::abs(t) + slack / glm::length(Vec3d(r.d));
}

/// Same primitive: t, (u, v) and normal must agree. For triangles the tolerances are in world units
/// (the float error of a test is a few ulps of the coordinates' magnitude), turned into t and
/// barycentrics through the angle between ray and plane: a grazing ray's t is ill-conditioned.
bool sameHitRecord(const SceneGeometry& g, const Ray& r, const Hit& a, const Hit& b, const ValidationTolerances& tol,
                   std::string& why) {
    Vec3d d(r.d);
    double dLen = glm::length(d);
    if (b.geomId == g.sphereGeomId()) {
        double tTol = tol.tRelative * std::abs(double(b.t)) + 1e-6 * glm::length(Vec3d(r.o)) / dLen +
                      4.0 * 0x1p-24 * g.spheres[b.primId].radius / dLen;
        if (std::abs(double(a.t) - double(b.t)) > tTol) return why = "t differs", false;
        if (glm::dot(a.ng, b.ng) < tol.normalCos) return why = "normal differs", false;
        float du = std::abs(a.u - b.u), dv = std::abs(a.v - b.v);
        du = std::min(du, 1.f - du);                   // φ wraps around
        bool pole = std::abs(b.ng.y) > 0.9999f;        // φ undefined at the poles
        if ((!pole && du > tol.uv) || dv > tol.uv) return why = "u, v differ", false;
        return true;
    }
    const TriangleMesh& m = g.meshes[b.geomId];
    const glm::uvec3& tri = m.triangles[b.primId];
    Vec3d p0(m.positions[tri.x]), e1 = Vec3d(m.positions[tri.y]) - p0, e2 = Vec3d(m.positions[tri.z]) - p0;
    double scale = std::max({glm::length(Vec3d(r.o)), glm::length(p0), glm::length(p0 + e1), glm::length(p0 + e2)});
    double slack = tol.edgeUlps * 0x1p-24 * (scale + std::abs(double(b.t)) * dLen) * conditionNumber(p0, p0 + e1, p0 + e2);
    Vec3d n = glm::normalize(glm::cross(e1, e2));
    double cosine = std::max(std::abs(glm::dot(n, d)) / dLen, 1e-6);
    double tTol = tol.tRelative * std::abs(double(b.t)) + slack / (cosine * dLen);
    if (std::abs(double(a.t) - double(b.t)) > tTol) return why = "t differs", false;
    if (glm::dot(a.ng, b.ng) < tol.normalCos) return why = "normal differs", false;
    double du = double(a.u) - double(b.u), dv = double(a.v) - double(b.v);
    bool uvClose = std::abs(du) <= tol.uv && std::abs(dv) <= tol.uv;
    if (!uvClose && glm::length(du * e1 + dv * e2) > slack / cosine) return why = "u, v differ", false;
    return true;
}

/// True when the tested hit's t and (u, v) are at least about as close to the double-precision
/// answer on that primitive as the reference's (within a factor 2 or 1e-7 relative).
bool closerToTruth(const SceneGeometry& g, const Ray& r, const Hit& test, const Hit& ref) {
    if (test.geomId == g.sphereGeomId()) {
        const Sphere& s = g.spheres[test.primId];
        double t = intersectSphere(s.center, s.radius, r);
        if (t < 0.0) return false;
        return std::abs(test.t - t) <= 2.0 * std::abs(ref.t - t) + 1e-7 * t;
    }
    const TriangleMesh& m = g.meshes[test.geomId];
    const glm::uvec3& tri = m.triangles[test.primId];
    double t, b1, b2;
    if (!planeHit(r, Vec3d(m.positions[tri.x]), Vec3d(m.positions[tri.y]), Vec3d(m.positions[tri.z]), t, b1, b2)) return false;
    auto within = [](double mine, double theirs, double truth, double scale) {
        return std::abs(mine - truth) <= 2.0 * std::abs(theirs - truth) + 1e-7 * scale;
    };
    return within(test.t, ref.t, t, std::abs(t)) && within(test.u, ref.u, b1, 1.0) && within(test.v, ref.v, b2, 1.0);
}

/// True when `h` lies on a cut-out triangle where its alpha mask drops the hit, confirmed in double
/// precision (not within rounding of the mask's cutoff contour): no backend may report it.
bool inCutOutHole(const SceneGeometry& g, const Ray& r, const Hit& h, const ValidationTolerances& tol) {
    if (h.geomId >= g.meshes.size() || !g.meshes[h.geomId].alphaMask) return false;
    PrimCheck c = checkPrimitive(g, r, h.geomId, h.primId, tol.edgeUlps);
    return !c.alphaKept && !c.alphaMarginal;
}

/// Classifies one ray. Returns 0 agreement, 1 tie, 2 error (with `why`).
/// Cut-out triangles: a reported hit must be kept by its alpha mask, and the rules below, written for
/// opaque primitives, then hold unchanged for the hits that count; in addition a hit that only one
/// answer has (or the nearer one of two) is a tie where its mask's answer is marginal.
int classify(const SceneGeometry& g, const Ray& r, bool th, const Hit& ht, bool rh, const Hit& hr,
             const ValidationTolerances& tol, std::string& why) {
    if (!th && !rh) return 0;
    if (th && inCutOutHole(g, r, ht, tol)) return why = "hit inside a cut-out hole (alpha mask)", 2;
    if (rh && inCutOutHole(g, r, hr, tol)) return why = "the reference hits inside a cut-out hole (alpha mask)", 2;
    if (th && rh && ht.geomId == hr.geomId && ht.primId == hr.primId) {
        if (sameHitRecord(g, r, ht, hr, tol, why)) return 0;
        // Ill-conditioned primitives (long slivers) put both float tests far from the truth: what
        // matters is that ours is no worse than the reference, judged in double precision.
        return closerToTruth(g, r, ht, hr) ? 1 : 2;
    }
    if (th != rh) {
        const Hit& h = th ? ht : hr;
        PrimCheck c = checkPrimitive(g, r, h.geomId, h.primId, tol.edgeUlps);
        if (c.nearBoundary || c.alphaMarginal) return 1;
        // A hit within the tolerance of tMin or tMax may be reported either way.
        double tTol = tTolerance(r, h.t, tol, c.slack);
        if (std::abs(double(h.t) - double(r.tMin)) <= tTol || std::abs(double(h.t) - double(r.tMax)) <= tTol) return 1;
        // Our hit confirmed in double precision, inside the primitive and the ray's range: the
        // reference is the one that missed.
        if (th && c.hitInside && c.t > double(r.tMin) && c.t < double(r.tMax)) return 1;
        why = th ? "hit where the reference misses" : "missed a hit of the reference";
        return 2;
    }
    // Different primitives: a tie when both are hit (or grazed) at the same distance, or when the
    // nearer one is only grazed at an edge (which either answer may include or skip).
    PrimCheck ct = checkPrimitive(g, r, ht.geomId, ht.primId, tol.edgeUlps);
    PrimCheck cr = checkPrimitive(g, r, hr.geomId, hr.primId, tol.edgeUlps);
    if (ct.t < 0.0 || cr.t < 0.0) return why = "different primitive, not hit in double precision", 2;
    double tTol = std::max(tTolerance(r, ct.t, tol, ct.slack), tTolerance(r, cr.t, tol, cr.slack));
    if (std::abs(ct.t - cr.t) <= tTol && std::abs(double(ht.t) - double(hr.t)) <= tTol) return 1;
    const PrimCheck& nearer = ct.t < cr.t ? ct : cr;
    if (nearer.nearBoundary || nearer.alphaMarginal) return 1;
    // Ours is a real hit (double precision) no farther than the reference's: the reference skipped it.
    if (ct.hitInside && ct.t > double(r.tMin) && ct.t <= cr.t + tTol) return 1;
    why = "different primitive at a different distance";
    return 2;
}

}  // namespace

void ValidationResult::merge(const ValidationResult& o, size_t maxExamples) {
    rays += o.rays;
    agreements += o.agreements;
    ties += o.ties;
    errors += o.errors;
    for (const ValidationExample& e : o.examples)
        if (examples.size() < maxExamples) examples.push_back(e);
}

ValidationResult compareAccels(const Accel& test, const Accel& reference, const SceneGeometry& g,
                               std::span<const Ray> rays, RayKind kind, const ValidationTolerances& tol,
                               size_t maxExamples) {
    constexpr size_t kChunk = 4096;
    size_t chunks = (rays.size() + kChunk - 1) / kChunk;
    std::vector<ValidationResult> partial(chunks);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
        ValidationResult& res = partial[c];
        for (size_t i = c * kChunk; i < std::min(rays.size(), (c + 1) * kChunk); ++i) {
            const Ray& r = rays[i];
            Hit ht, hr;
            bool th = test.intersect(r, ht), rh = reference.intersect(r, hr);
            std::string why;
            int verdict = classify(g, r, th, ht, rh, hr, tol, why);
            if (verdict != 2 && test.occluded(r) != th) verdict = 2, why = "occluded() disagrees with intersect()";
            Hit hc;
            bool ch = test.intersectCoherent(r, hc);
            if (verdict != 2 && !sameRecord(th, ht, ch, hc)) verdict = 2, why = "intersectCoherent() disagrees with intersect()";
            ++res.rays;
            if (verdict == 0) ++res.agreements;
            else if (verdict == 1) ++res.ties;
            else {
                ++res.errors;
                if (res.examples.size() < maxExamples) res.examples.push_back({kind, i, r, th, rh, ht, hr, why});
            }
        }
    });
    ValidationResult total;
    for (const ValidationResult& p : partial) total.merge(p, maxExamples);
    return total;
}

nlohmann::json toJson(const Ray& r) {
    return {{"o", {r.o.x, r.o.y, r.o.z}}, {"d", {r.d.x, r.d.y, r.d.z}}, {"tMin", r.tMin},
            {"tMax", std::isinf(r.tMax) ? nlohmann::json("inf") : nlohmann::json(r.tMax)}};
}

nlohmann::json toJson(const Hit& h, bool found) {
    if (!found) return nullptr;
    return {{"t", h.t}, {"u", h.u}, {"v", h.v}, {"primId", h.primId}, {"geomId", h.geomId}, {"ng", {h.ng.x, h.ng.y, h.ng.z}}};
}

nlohmann::json toJson(const ValidationResult& r) {
    nlohmann::json examples = nlohmann::json::array();
    for (const ValidationExample& e : r.examples)
        examples.push_back({{"kind", std::string(toString(e.kind))}, {"ray_index", e.rayIndex}, {"ray", toJson(e.ray)},
                            {"reason", e.reason}, {"test", toJson(e.test, e.testHit)}, {"reference", toJson(e.ref, e.refHit)}});
    return {{"rays", r.rays}, {"agreements", r.agreements}, {"ties", r.ties}, {"errors", r.errors}, {"examples", examples}};
}

}  // namespace tessera
