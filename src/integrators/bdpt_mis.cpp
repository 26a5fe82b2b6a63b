#include "integrators/bdpt_mis.h"

#include <cmath>

namespace tessera {

float bdptMisWeight(std::span<const MisVertex> light, std::span<const MisVertex> camera, bool lightIsDelta,
                    MisHeuristic heuristic, float neeOverOriginA) {
    const int s = int(light.size()), t = int(camera.size());
    auto remap0 = [](float p) { return p != 0.f ? double(p) : 1.0; };
    auto powBeta = [heuristic](double r) { return heuristic == MisHeuristic::Power ? r * r : r; };
    double sumRatios = 0.0;  // Σ_{i≠s} (p_i / p_s)^β, eq. 10.10
    // (p_1 / p_1 of the chain)^β: strategy s = 1's own light-point density (see the header).
    const double neeFactor = powBeta(neeOverOriginA > 0.f ? double(neeOverOriginA) : 1.0);

    // Strategies with fewer camera vertices: z(t−1), z(t−2), … become light-sampled one by one.
    // Strategy t' = j connects z(j−1)–z(j), so both must be connectible; t' = 0 (hitting the lens)
    // is not a strategy of ours.
    double ratio = 1.0;
    for (int j = t - 1; j > 0; --j) {
        ratio *= powBeta(remap0(camera[j].pdfRevA) / remap0(camera[j].pdfFwdA));
        if (!camera[j].delta && !camera[j - 1].delta) sumRatios += s == 0 && j == t - 1 ? ratio * neeFactor : ratio;
    }
    // Strategies with fewer light vertices: y(s−1), y(s−2), … become camera-sampled. Strategy
    // s' = j connects y(j−1)–y(j); s' = 0 needs y0 to be hittable (not a point light).
    ratio = 1.0;
    for (int j = s - 1; j >= 0; --j) {
        ratio *= powBeta(remap0(light[j].pdfRevA) / remap0(light[j].pdfFwdA));
        bool prevDelta = j > 0 ? light[j - 1].delta : lightIsDelta;
        if (!light[j].delta && !prevDelta) sumRatios += j == 1 ? ratio * neeFactor : ratio;
    }
    if (s == 1) sumRatios /= neeFactor;  // every other p_i is relative to p_1 itself
    return float(1.0 / (1.0 + sumRatios));
}

}  // namespace tessera
