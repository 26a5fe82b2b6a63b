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
double lineSegmentDistance(const Vec3d& o, const Vec3d& d, const Vec3d& a, const Vec3d& b) {
    Vec3d e = b - a, w0 = a - o;
    double dd = glm::dot(d, d), ee = glm::dot(e, e), de = glm::dot(d, e), dw = glm::dot(d, w0), ew = glm::dot(e, w0);
    double den = dd * ee - de * de;
    double s = den > 1e-300 * dd * ee ? (de * dw - dd * ew) / den : 0.0;  // segment parameter
    s = std::clamp(s, 0.0, 1.0);
    Vec3d q = a + s * e;
    double lineS = glm::dot(q - o, d) / dd;
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

/// What double precision says about a primitive along a ray. Rounding lets a float test place a
/// triangle's plane anywhere within `slack` (world units: ulps of the magnitude times the triangle's
/// condition number) and its edges within ulps of the magnitude, and, for a ray nearly in its plane,
/// report (u, v) that are rounding noise. So the ray *touches* the primitive over an interval of
/// distances [tLo, tHi] where a float test may report a hit; the hit is *certain* when the ray
/// crosses it farther than those bounds from its boundary.
struct PrimCheck {
    bool hitInside = false;     ///< crossed inside, farther than the bounds from every edge (sphere: from the silhouette)
    bool nearBoundary = false;  ///< within ulps of the magnitude of an edge (sphere: of the silhouette)
    double tLo = kInfinity, tHi = -kInfinity;  ///< the touched distances; empty when tLo > tHi
    double slack = 0.0;
    /// Cut-out triangles (alpha mask): whether the mask keeps the point where the ray meets the
    /// plane, and whether that answer could flip within `slack` of it (a point on the mask's cutoff
    /// contour, or no point at all for a ray parallel to the plane), where keeping and dropping the
    /// hit are both admissible. Opaque primitives: kept, never marginal.
    bool alphaKept = true;
    bool alphaMarginal = false;
    bool touched() const { return tLo <= tHi; }
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

/// Clips the parameter interval [lo, hi] of the line o + t·d to the half-space n·x ≤ offset.
void clipToHalfSpace(const Vec3d& o, const Vec3d& d, const Vec3d& n, double offset, double& lo, double& hi) {
    double a = glm::dot(n, o) - offset, b = glm::dot(n, d);  // a + b·t ≤ 0
    if (b == 0.0) {
        if (a > 0.0) lo = kInfinity, hi = -kInfinity;
    } else if (b > 0.0) {
        hi = std::min(hi, -a / b);
    } else {
        lo = std::max(lo, -a / b);
    }
}

/// The distances at which the ray passes within `slack` of a triangle: the line clipped to the
/// triangle's prism grown by slack (its plane's slab and the three edge half-planes, each moved out by
/// slack) and to its bounding box grown by slack, which caps the long spikes that moving the edges
/// out gives a sliver's sharp corners. Cyrus–Beck clipping, in double precision.
void touchedInterval(const Ray& r, const Vec3d (&p)[3], double slack, double& lo, double& hi) {
    Vec3d o(r.o), d(r.d);
    lo = -kInfinity, hi = kInfinity;
    Vec3d n = glm::cross(p[1] - p[0], p[2] - p[0]);
    double area2 = glm::length(n);
    if (area2 > 0.0) {
        n /= area2;
        clipToHalfSpace(o, d, n, glm::dot(n, p[0]) + slack, lo, hi);
        clipToHalfSpace(o, d, -n, -glm::dot(n, p[0]) + slack, lo, hi);
        for (int e = 0; e < 3; ++e) {
            Vec3d out = glm::normalize(glm::cross(p[(e + 1) % 3] - p[e], n));  // in the plane, away from the third vertex
            clipToHalfSpace(o, d, out, glm::dot(out, p[e]) + slack, lo, hi);
        }
    }
    for (int axis = 0; axis < 3; ++axis) {
        Vec3d unit(0.0);
        unit[axis] = 1.0;
        double bMin = std::min({p[0][axis], p[1][axis], p[2][axis]}), bMax = std::max({p[0][axis], p[1][axis], p[2][axis]});
        clipToHalfSpace(o, d, unit, bMax + slack, lo, hi);
        clipToHalfSpace(o, d, -unit, -bMin + slack, lo, hi);
    }
}

/// How far a float triangle test's barycentrics may be from the exact ones: its edge functions are
/// 2-D cross products of vertices relative to the origin (magnitude S²), rounded to a few ulps of
/// S², and divided by twice the triangle's area projected along the ray (area2 · cos θ). Bounded
/// as in Woop et al. 2013 (watertight test, §4) with 8 ulps; it reaches 1 for a ray in a sliver's
/// plane, where a float test returns rounding noise for (u, v) and a t among the vertices'.
double barycentricNoise(const Ray& r, const Vec3d (&p)[3]) {
    Vec3d o(r.o), d(r.d), n = glm::cross(p[1] - p[0], p[2] - p[0]);
    double s2 = 0.0;
    for (const Vec3d& q : p) s2 = std::max(s2, glm::dot(q - o, q - o));
    double projectedArea2 = std::abs(glm::dot(n, d)) / glm::length(d);
    return projectedArea2 > 0.0 ? 8.0 * 0x1p-24 * s2 / projectedArea2 : kInfinity;
}

/// `reportedT` chooses, for a sphere, which of its two crossings a record refers to.
PrimCheck checkPrimitive(const SceneGeometry& g, const Ray& r, uint32_t geomId, uint32_t primId, float edgeUlps,
                         double reportedT) {
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
        // Rounding moves an ill-conditioned triangle's plane (so t) by up to `slack`, its edges in the
        // plane only by ulps of the magnitude: a sliver is certainly hit across its middle.
        double edgeSlack = edgeUlps * 0x1p-24 * (scale + (plane ? std::abs(t) * dLen : 0.0));
        c.slack = edgeSlack * conditionNumber(p[0], p[1], p[2]);
        touchedInterval(r, p, c.slack, c.tLo, c.tHi);
        double edgeDist = kInfinity;
        for (int e = 0; e < 3; ++e) edgeDist = std::min(edgeDist, lineSegmentDistance(o, d, p[e], p[(e + 1) % 3]));
        c.nearBoundary = edgeDist <= edgeSlack;
        if (!plane) {
            c.alphaMarginal = bool(m.alphaMask);  // parallel to the plane: no single point to evaluate the mask at
            return c;
        }
        if (m.alphaMask) checkAlpha(m, primId, p, r, b1, b2, c);
        double bNoise = barycentricNoise(r, p), b0 = 1.0 - b1 - b2;
        c.hitInside = std::min({b0, b1, b2}) > bNoise && !c.nearBoundary;
        if (std::min({b0, b1, b2}) >= -bNoise) {
            // The crossing is within the float test's barycentric noise of the triangle: a hit there
            // is admissible, at a t the noise moves among the vertices' distances along the ray — a
            // weighted mean of them, measured along the ray's direction or, in a watertight test, along
            // its dominant axis (Woop et al. 2013).
            int k = std::abs(d.x) >= std::abs(d.y) ? (std::abs(d.x) >= std::abs(d.z) ? 0 : 2) : (std::abs(d.y) >= std::abs(d.z) ? 1 : 2);
            double spread = 0.0, zLo = kInfinity, zHi = -kInfinity;
            for (const Vec3d& q : p)
                for (double z : {glm::dot(q - o, d) / (dLen * dLen), (q[k] - o[k]) / d[k]}) {
                    spread = std::max(spread, std::abs(z - t));
                    zLo = std::min(zLo, z), zHi = std::max(zHi, z);
                }
            double dt = 2.0 * bNoise * spread;
            c.tLo = std::min(c.tLo, std::max(t - dt, zLo));
            c.tHi = std::max(c.tHi, std::min(t + dt, zHi));
        }
        return c;
    }
    // A sphere: the ray touches it where it is within slack of the surface, between the spheres of
    // radius r − slack and r + slack; near the silhouette (missing the inner one) over one chord.
    const Sphere& s = g.spheres[primId];
    Vec3d ctr(s.center);
    double scale = std::max(glm::length(o), glm::length(ctr) + s.radius);
    c.slack = edgeUlps * 0x1p-24 * scale;
    double out0, out1, in0, in1;
    if (!sphereRoots(o, d, ctr, double(s.radius) + c.slack, out0, out1)) return c;
    double inner = double(s.radius) - c.slack;
    if (inner > 0.0 && sphereRoots(o, d, ctr, inner, in0, in1)) {
        bool farSide = std::abs(reportedT - 0.5 * (in1 + out1)) < std::abs(reportedT - 0.5 * (out0 + in0));
        c.tLo = farSide ? in1 : out0;
        c.tHi = farSide ? out1 : in0;
        c.hitInside = true;
    } else {
        c.tLo = out0, c.tHi = out1;
        c.nearBoundary = true;
    }
    return c;
}

/// The touched interval widened by the relative t tolerance.
double paddedLo(const PrimCheck& c, const ValidationTolerances& tol) { return c.tLo - tol.tRelative * std::abs(c.tLo); }
double paddedHi(const PrimCheck& c, const ValidationTolerances& tol) { return c.tHi + tol.tRelative * std::abs(c.tHi); }

/// A hit every correct answer must report (or beat): crossed well inside, kept by any alpha mask,
/// and in the ray's range whatever rounding does to t. Any other touched primitive may be skipped.
bool certainHit(const PrimCheck& c, const Ray& r, const ValidationTolerances& tol) {
    return c.hitInside && !c.alphaMarginal && c.alphaKept && paddedLo(c, tol) > double(r.tMin) &&
           paddedHi(c, tol) < double(r.tMax);
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
    PrimCheck c = checkPrimitive(g, r, h.geomId, h.primId, tol.edgeUlps, h.t);
    return !c.alphaKept && !c.alphaMarginal;
}

enum class Verdict {
    Agree,
    Tie,
    Error,
    /// The reference's record is a hit any answer may skip (marginal), and the tested record lies
    /// behind it or is a miss: what the reference finds past that hit decides.
    AdvanceReference,
};

/// Classifies one ray (`why` names an error).
/// Cut-out triangles: a reported hit must be kept by its alpha mask, and the rules below, written for
/// opaque primitives, then hold unchanged for the hits that count; in addition a hit whose mask's
/// answer is marginal may be reported or skipped.
Verdict classify(const SceneGeometry& g, const Ray& r, bool th, const Hit& ht, bool rh, const Hit& hr,
                 const ValidationTolerances& tol, std::string& why) {
    if (!th && !rh) return Verdict::Agree;
    if (th && inCutOutHole(g, r, ht, tol)) return why = "hit inside a cut-out hole (alpha mask)", Verdict::Error;
    if (rh && inCutOutHole(g, r, hr, tol)) return why = "the reference hits inside a cut-out hole (alpha mask)", Verdict::Error;
    if (th && rh && ht.geomId == hr.geomId && ht.primId == hr.primId) {
        if (sameHitRecord(g, r, ht, hr, tol, why)) return Verdict::Agree;
        // Ill-conditioned primitives (long slivers) put both float tests far from the truth: what
        // matters is that ours is no worse than the reference, judged in double precision.
        return closerToTruth(g, r, ht, hr) ? Verdict::Tie : Verdict::Error;
    }
    PrimCheck ct, cr;
    if (th) {
        // The tested record must be a touch of its primitive, at a distance where the ray touches it.
        ct = checkPrimitive(g, r, ht.geomId, ht.primId, tol.edgeUlps, ht.t);
        if (!ct.touched()) return why = "hit a primitive the ray does not meet (double precision)", Verdict::Error;
        if (double(ht.t) < paddedLo(ct, tol) || double(ht.t) > paddedHi(ct, tol))
            return why = "t is not where the ray meets the primitive (double precision)", Verdict::Error;
    }
    if (rh) cr = checkPrimitive(g, r, hr.geomId, hr.primId, tol.edgeUlps, hr.t);
    if (!rh) return Verdict::Tie;  // ours is a touch the reference skipped, a real hit or a marginal one
    if (!th) {
        if (certainHit(cr, r, tol)) return why = "missed a hit of the reference", Verdict::Error;
        return Verdict::AdvanceReference;
    }
    // Different primitives. A reference record that does not even touch its primitive is wrong;
    // one in front of ours is passed over, one behind it is moot.
    if (!cr.touched()) return hr.t < ht.t ? Verdict::AdvanceReference : Verdict::Tie;
    double testLo = paddedLo(ct, tol), testHi = paddedHi(ct, tol), refLo = paddedLo(cr, tol), refHi = paddedHi(cr, tol);
    // Overlapping intervals: both may be the nearest (coplanar or duplicated triangles, a shared edge,
    // a grazing ray). Ours entirely in front: the reference skipped a touch.
    if (testLo <= refHi && refLo <= testHi) return Verdict::Tie;
    if (testHi < refLo) return Verdict::Tie;
    // The reference's primitive lies entirely in front of ours: ours missed it unless it may be skipped.
    if (certainHit(cr, r, tol)) return why = "different primitive at a different distance", Verdict::Error;
    return Verdict::AdvanceReference;
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
    constexpr int kMaxAdvances = 16;
    size_t chunks = (rays.size() + kChunk - 1) / kChunk;
    std::vector<ValidationResult> partial(chunks);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
        ValidationResult& res = partial[c];
        for (size_t i = c * kChunk; i < std::min(rays.size(), (c + 1) * kChunk); ++i) {
            const Ray& r = rays[i];
            Hit ht, hr;
            bool th = test.intersect(r, ht), rh = reference.intersect(r, hr);
            std::string why;
            Verdict verdict = classify(g, r, th, ht, rh, hr, tol, why);
            // Pass over the reference's marginal hits (a sliver it hits behind the origin, an edge it
            // grazes) to what it finds behind them, which ours must then match.
            Ray past = r;
            for (int step = 0; verdict == Verdict::AdvanceReference; ++step) {
                if (step == kMaxAdvances) {
                    verdict = Verdict::Tie;  // a ray through that many marginal hits decides nothing
                    break;
                }
                past.tMin = std::nextafter(std::max(hr.t, past.tMin), kInfinity);
                rh = reference.intersect(past, hr);
                verdict = classify(g, r, th, ht, rh, hr, tol, why);
                if (verdict == Verdict::Agree) verdict = Verdict::Tie;
            }
            if (verdict != Verdict::Error && test.occluded(r) != th) verdict = Verdict::Error, why = "occluded() disagrees with intersect()";
            Hit hc;
            bool ch = test.intersectCoherent(r, hc);
            if (verdict != Verdict::Error && !sameRecord(th, ht, ch, hc))
                verdict = Verdict::Error, why = "intersectCoherent() disagrees with intersect()";
            ++res.rays;
            if (verdict == Verdict::Agree) ++res.agreements;
            else if (verdict == Verdict::Tie) ++res.ties;
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
