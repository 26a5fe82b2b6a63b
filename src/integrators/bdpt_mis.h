#pragma once
/// \file bdpt_mis.h
/// The multiple-importance-sampling weight of one BDPT strategy, written once, as a pure function
/// of the densities along the path, so that tests can call it on paths they build themselves.
#include <span>

namespace tessera {

/// The two densities of one path vertex as the MIS weight needs them, *after* the connection of
/// the strategy being weighted has been made (the endpoints' and their neighbours' pdfRevA
/// recomputed for the connection, Veach 1997, §10.2).
struct MisVertex {
    float pdfFwdA = 0.f;  ///< density of being sampled from its own sub-path's side (0 = delta)
    float pdfRevA = 0.f;  ///< density of being sampled from the other side (0 = delta)
    bool delta = false;   ///< scattered by a delta BSDF: no connection may end here
};

enum class MisHeuristic { Balance, Power };

/// MIS weight of strategy (s, t) for the path y0 … y(s−1) z(t−1) … z0, with `light` = y0 … y(s−1)
/// and `camera` = z0 … z(t−1) (both in sampling order). `lightIsDelta`: y0 is a delta in position
/// (point light), so no camera sub-path can hit it (strategy s = 0 impossible for it).
///
/// Derivation (Veach 1997, §10.2.2, eqs. 10.9–10.10). Let x0 … x(k) be the path (x0 on the light,
/// k = s + t − 1) and p_i the area-product density of generating it with i light vertices and
/// k + 1 − i camera vertices:   p_i = Π_{j<i} p→(x_j) · Π_{j≥i} p←(x_j),
/// where p→ is a vertex's density from the light side and p← from the camera side. Neighbouring
/// strategies differ in one vertex only, so
///     p_{i+1} / p_i = p→(x_i) / p←(x_i).
/// On the camera sub-path x_i = z_j has p← = pdfFwdA and p→ = pdfRevA; on the light sub-path the
/// roles swap. The weight with heuristic exponent β (1 = balance, 2 = power, Veach eq. 9.13) is
///     w_s = p_s^β / Σ_i p_i^β = 1 / (1 + Σ_{i≠s} (p_i / p_s)^β),
/// and each (p_i / p_s) is a running product of pdfRevA/pdfFwdA ratios walking away from the
/// connection on either sub-path. Terms whose strategy would connect at a delta vertex are left out
/// (such a strategy has density 0). A density after a delta scattering is the delta's unit weight
/// converted to area (path_vertex.h's deltaDensityA): the same delta factor appears in both
/// densities of a ratio and cancels (Veach 1997, §10.3.5), its |cos|/d² does not. A density of 0
/// (a vertex behind a one-sided emitter) is remapped to 1 (pbrt's remap0).
///
/// Strategy s = 1 samples x0 by next-event estimation, not by the light sub-path's origin
/// sampling that strategies s ≥ 2 use: for a sphere light the visible cone from x1, whose area
/// density at x0 differs from the sphere's uniform area density. The chain above uses the origin
/// density p→(x0) for every strategy; `neeOverOriginA` = p_NEE(x0 | x1) / p→(x0) (both area
/// densities, 1 where they agree: triangle, point and infinite lights) corrects the one density
/// that differs: p_1 = neeOverOriginA · (p_1 of the chain). Every strategy of a path computes the
/// same factor, so the weights still sum to one and the s = 1 weight uses the density that
/// strategy was actually sampled with (as Mitsuba 0.6's BDPT does for its direct-sampling
/// strategy).
float bdptMisWeight(std::span<const MisVertex> light, std::span<const MisVertex> camera, bool lightIsDelta,
                    MisHeuristic heuristic, float neeOverOriginA = 1.f);

/// The same weight in O(1) per strategy: the recursive form of the sums above (Georgiev et al.
/// 2012, "Light transport simulation with vertex connection and merging", and its technical report
/// I. Georgiev, "Implementing Vertex Connection and Merging", 2012: the quantities dVC/dVCM carried
/// along each sub-path, initialised by eqs. 31–33, updated per vertex by eqs. 34–36 and combined
/// into a connection's weight by eqs. 37–41). On a sub-path v_0 … v_(n−1) (sampling order) let
/// r_j = (pdfRevA_j / pdfFwdA_j)^β and
///     M_j = r_j · (c_j g_j + M_(j−1)),   M_(−1) = 0,                                  (†)
/// with c_j = 1 when the strategy connecting v_(j−1) and v_j exists (neither is delta; for y0: the
/// light is not a delta in position; for the lens z0: never) and g_j the s = 1 factor
/// neeOverOriginA^β at y1 (1 elsewhere). Walking away from the connection, the sub-path's share of
/// Σ_{i≠s} (p_i / p_s)^β is the term of v_(n−1), that of v_(n−2), and r_(n−1) r_(n−2) · M_(n−3)
/// for all the strategies further out. Only v_(n−1) and v_(n−2) have densities the connection
/// changes, so every M_j further out is fixed once the walks are done: misPrefixStep computes (†)
/// per vertex and bdptMisWeightFromEnds adds the two updated vertices of each side. The same sums as
/// the loop form, added in another order (double precision, as the loop).
namespace mis_detail {
inline double remap0(float p) { return p != 0.f ? double(p) : 1.0; }
inline double powBeta(double r, MisHeuristic heuristic) { return heuristic == MisHeuristic::Power ? r * r : r; }
/// r_j of (†): (pdfRevA / pdfFwdA)^β.
inline double ratioOf(const MisVertex& v, MisHeuristic heuristic) { return powBeta(remap0(v.pdfRevA) / remap0(v.pdfFwdA), heuristic); }
}  // namespace mis_detail

/// g_1 of (†): neeOverOriginA^β (1 where it is not positive).
inline double misNeeFactor(float neeOverOriginA, MisHeuristic heuristic) {
    return mis_detail::powBeta(neeOverOriginA > 0.f ? double(neeOverOriginA) : 1.0, heuristic);
}

/// Vertex merging (VCM, Georgiev et al. 2012) adds one strategy per interior vertex x_i of a path:
/// the light sub-path reaches x_i, the camera sub-path ends within the merge radius r of it. Its
/// density is that of the connection with x_i on the light side times p←(x_i) · η, where
/// η = N π r² (N light sub-paths per iteration against one connected, the tech report's
/// η_VCM = n_VM π r² / n_VC, eq. 21). Relative to its neighbours in (†) it adds
///     μ_j = m_j (η · pdfFwdA_j)^β,   M_j = r_j · (c_j g_j + μ_j + M_(j−1)),                 (‡)
/// m_j = 1 where the path scatters through a non-delta lobe at v_j and v_j is interior (not y0 or
/// the lens, not at infinity). η = 0 gives back (†) exactly (bdpt). The tech report's dVM is this
/// sum's merging part; its eqs. 34–36 are (‡) with the area-conversion factors moved between
/// vertices.
inline double misMergeTerm(bool merges, float pdfFwdA, double eta, MisHeuristic heuristic) {
    return merges && eta > 0.0 ? mis_detail::powBeta(eta * mis_detail::remap0(pdfFwdA), heuristic) : 0.0;
}

/// The bracket of (‡), c_j g_j + μ_j + M_(j−1): what the strategies at and beyond v_j add before the ratio r_j.
inline double misPrefixTerm(double prefixBefore, bool connectibleTerm, double g, double mergeTerm) {
    return (connectibleTerm ? g : 0.0) + mergeTerm + prefixBefore;
}

/// M_j of (‡) from M_(j−1) = `prefixBefore`, the vertex's densities, c_j, g_j and μ_j.
inline double misPrefixStep(double prefixBefore, const MisVertex& v, bool connectibleTerm, double g, MisHeuristic heuristic,
                            double mergeTerm = 0.0) {
    return mis_detail::ratioOf(v, heuristic) * misPrefixTerm(prefixBefore, connectibleTerm, g, mergeTerm);
}

/// The last vertices of one sub-path as a strategy's weight needs them: `end` = v(n−1) and
/// `next` = v(n−2) with the densities the connection changes already updated, `prefix` = M_(n−3)
/// (0 when n < 3) and `nextPrevDelta` whether v(n−3) is delta (for the light sub-path with n = 2:
/// whether the light is a delta in position; for the camera sub-path with n = 2: false).
struct MisEnds {
    int n = 0;  ///< vertices of the sub-path in the strategy (s or t)
    MisVertex end, next;
    double prefix = 0.0;
    bool nextPrevDelta = false;
    /// VCM only (η > 0): m of (‡) for `end` and `next`, whether a merge at them is a strategy of the path.
    bool endMerges = false, nextMerges = false;
};

/// bdptMisWeight from the sub-paths' ends: O(1). `light.n` = s, `camera.n` = t. Inline: it runs
/// once per connection, and inlined into the caller the two MisEnds never leave registers. With
/// `eta` > 0 the merging strategies of (‡) join the sum (VCM's connection weight, tech report eq. 40).
inline float bdptMisWeightFromEnds(const MisEnds& light, const MisEnds& camera, bool lightIsDelta, MisHeuristic heuristic,
                                   float neeOverOriginA = 1.f, double eta = 0.0) {
    using mis_detail::ratioOf;
    const int s = light.n, t = camera.n;
    double sumRatios = 0.0;  // Σ_{i≠s} (p_i / p_s)^β, eq. 10.10
    // (p_1 / p_1 of the chain)^β: strategy s = 1's own light-point density (see bdptMisWeight).
    const double neeFactor = misNeeFactor(neeOverOriginA, heuristic);

    // Strategies with fewer camera vertices: z(t−1), z(t−2), … become light-sampled one by one.
    // Strategy t' = j connects z(j−1)–z(j), so both must be connectible; t' = 0 (hitting the lens)
    // is not a strategy of ours (the lens's c_0 = 0, so M_0 = 0).
    if (t >= 2) {
        double ratio = ratioOf(camera.end, heuristic);
        if (!camera.end.delta && !camera.next.delta) sumRatios += s == 0 ? ratio * neeFactor : ratio;
        if (eta > 0.0) sumRatios += ratio * misMergeTerm(camera.endMerges, camera.end.pdfFwdA, eta, heuristic);
        if (t >= 3) {
            ratio *= ratioOf(camera.next, heuristic);
            if (!camera.next.delta && !camera.nextPrevDelta) sumRatios += ratio;
            if (eta > 0.0) sumRatios += ratio * misMergeTerm(camera.nextMerges, camera.next.pdfFwdA, eta, heuristic);
            sumRatios += ratio * camera.prefix;  // t' ≤ t − 3, eq. (†)
        }
    }
    // Strategies with fewer light vertices: y(s−1), y(s−2), … become camera-sampled. Strategy
    // s' = j connects y(j−1)–y(j); s' = 0 needs y0 to be hittable (not a point light).
    if (s >= 1) {
        double ratio = ratioOf(light.end, heuristic);
        bool prevDelta = s >= 2 ? light.next.delta : lightIsDelta;
        if (!light.end.delta && !prevDelta) sumRatios += s - 1 == 1 ? ratio * neeFactor : ratio;
        if (eta > 0.0) sumRatios += ratio * misMergeTerm(light.endMerges, light.end.pdfFwdA, eta, heuristic);
        if (s >= 2) {
            ratio *= ratioOf(light.next, heuristic);
            if (!light.next.delta && !light.nextPrevDelta) sumRatios += s - 2 == 1 ? ratio * neeFactor : ratio;
            if (eta > 0.0) sumRatios += ratio * misMergeTerm(light.nextMerges, light.next.pdfFwdA, eta, heuristic);
            sumRatios += ratio * light.prefix;  // s' ≤ s − 3, eq. (†) with g_1 = neeFactor
        }
    }
    if (s == 1) sumRatios /= neeFactor;  // every other p_i is relative to p_1 itself
    return float(1.0 / (1.0 + sumRatios));
}

}  // namespace tessera
