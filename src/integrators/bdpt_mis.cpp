#include "integrators/bdpt_mis.h"

#include <cmath>

namespace tessera {
namespace {

double remap0(float p) { return p != 0.f ? double(p) : 1.0; }
double powBeta(double r, MisHeuristic heuristic) { return heuristic == MisHeuristic::Power ? r * r : r; }
double ratioOf(const MisVertex& v, MisHeuristic heuristic) { return powBeta(remap0(v.pdfRevA) / remap0(v.pdfFwdA), heuristic); }

}  // namespace

double misNeeFactor(float neeOverOriginA, MisHeuristic heuristic) {
    return powBeta(neeOverOriginA > 0.f ? double(neeOverOriginA) : 1.0, heuristic);
}

double misPrefixStep(double prefixBefore, const MisVertex& v, bool connectibleTerm, double g, MisHeuristic heuristic) {
    return ratioOf(v, heuristic) * ((connectibleTerm ? g : 0.0) + prefixBefore);
}

float bdptMisWeightFromEnds(const MisEnds& light, const MisEnds& camera, bool lightIsDelta, MisHeuristic heuristic,
                            float neeOverOriginA) {
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
        if (t >= 3) {
            ratio *= ratioOf(camera.next, heuristic);
            if (!camera.next.delta && !camera.nextPrevDelta) sumRatios += ratio;
            sumRatios += ratio * camera.prefix;  // t' ≤ t − 3, eq. (†)
        }
    }
    // Strategies with fewer light vertices: y(s−1), y(s−2), … become camera-sampled. Strategy
    // s' = j connects y(j−1)–y(j); s' = 0 needs y0 to be hittable (not a point light).
    if (s >= 1) {
        double ratio = ratioOf(light.end, heuristic);
        bool prevDelta = s >= 2 ? light.next.delta : lightIsDelta;
        if (!light.end.delta && !prevDelta) sumRatios += s - 1 == 1 ? ratio * neeFactor : ratio;
        if (s >= 2) {
            ratio *= ratioOf(light.next, heuristic);
            if (!light.next.delta && !light.nextPrevDelta) sumRatios += s - 2 == 1 ? ratio * neeFactor : ratio;
            sumRatios += ratio * light.prefix;  // s' ≤ s − 3, eq. (†) with g_1 = neeFactor
        }
    }
    if (s == 1) sumRatios /= neeFactor;  // every other p_i is relative to p_1 itself
    return float(1.0 / (1.0 + sumRatios));
}

float bdptMisWeight(std::span<const MisVertex> light, std::span<const MisVertex> camera, bool lightIsDelta,
                    MisHeuristic heuristic, float neeOverOriginA) {
    const int s = int(light.size()), t = int(camera.size());
    const double neeFactor = misNeeFactor(neeOverOriginA, heuristic);
    MisEnds l, c;
    l.n = s;
    c.n = t;
    // The prefixes (†) up to the third vertex from each end.
    for (int j = 0; j + 3 <= s; ++j) {
        bool prevDelta = j > 0 ? light[size_t(j - 1)].delta : lightIsDelta;
        l.prefix = misPrefixStep(l.prefix, light[size_t(j)], !light[size_t(j)].delta && !prevDelta, j == 1 ? neeFactor : 1.0, heuristic);
    }
    for (int j = 1; j + 3 <= t; ++j)
        c.prefix = misPrefixStep(c.prefix, camera[size_t(j)], !camera[size_t(j)].delta && !camera[size_t(j - 1)].delta, 1.0, heuristic);
    if (s >= 1) l.end = light[size_t(s - 1)];
    if (s >= 2) l.next = light[size_t(s - 2)];
    l.nextPrevDelta = s >= 3 ? light[size_t(s - 3)].delta : lightIsDelta;
    if (t >= 1) c.end = camera[size_t(t - 1)];
    if (t >= 2) c.next = camera[size_t(t - 2)];
    c.nextPrevDelta = t >= 3 && camera[size_t(t - 3)].delta;
    return bdptMisWeightFromEnds(l, c, lightIsDelta, heuristic, neeOverOriginA);
}

}  // namespace tessera
