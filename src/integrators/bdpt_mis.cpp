#include "integrators/bdpt_mis.h"

#include <cmath>

namespace tessera {
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
