#pragma once
/// \file bdpt_connect.h
/// One BDPT strategy (s, t): joins the first s vertices of a light sub-path with the first t of a
/// camera sub-path and returns the unweighted contribution together with its MIS weight.
/// Strategies (Veach 1997, §10.2):
///   s = 0:  the camera sub-path hit an emitter at z(t−1);
///   s = 1:  a light point is resampled from z(t−1) (next-event estimation) instead of using y0;
///   t = 1:  a lens point is resampled from y(s−1) and the contribution lands on another pixel;
///   else:   y(s−1) and z(t−1) are joined by a shadow ray.
#include <span>

#include "integrators/bdpt_mis.h"
#include "integrators/path_vertex.h"

namespace tessera {

struct ConnectionResult {
    Rgb L{0.f};          ///< unweighted contribution C*_{s,t} (Veach eq. 10.8 without the weight)
    float weight = 0.f;  ///< MIS weight w_{s,t}
    Vec2f raster{0.f};   ///< for t = 1: where it lands on the film
};

/// Evaluates strategy (s, t) on the given sub-paths (s ≤ light.size(), 1 ≤ t ≤ camera.size(),
/// s + t ≥ 2). Draws random numbers only for s = 1 (light point) and t = 1 (lens point). With
/// `computeWeight` false the weight is left at 1 (light tracing uses t = 1 alone). `eta` > 0: VCM's
/// weight, merging strategies included (bdpt_mis.h's (‡); η = N π r²).
ConnectionResult connectBdpt(const RenderContext& ctx, std::span<const PathVertex> light,
                             std::span<const PathVertex> camera, int s, int t, Sampler& sampler,
                             MisHeuristic heuristic, bool computeWeight = true, double eta = 0.0);

/// Fills PathVertex::misPrefix along both sub-paths (bdpt_mis.h's M_j): once per sample, after
/// both walks, before any weight of the sample is computed; O(s + t), so that every weight is O(1).
/// `eta` > 0 adds VCM's merging strategies (bdpt_mis.h's (‡)).
void bdptMisPrefixes(const RenderContext& ctx, std::span<PathVertex> light, std::span<PathVertex> camera, MisHeuristic heuristic,
                     double eta = 0.0);

/// g_1 of bdpt_mis.h's (†) for a light sub-path y0 y1 …: strategy s = 1's density ratio at y0
/// given y1, to the power β (1 when the sub-path has fewer than two vertices).
double bdptLightNeeFactor(const RenderContext& ctx, std::span<const PathVertex> light, MisHeuristic heuristic);

/// The densities a connection changes (pbrt-v3 §16.3.4's "pdfRev" updates, Veach 1997, §10.2), all
/// area densities, with y(s−1) = `qs` and z(t−1) = `pt` the endpoints actually used.
struct ConnectionDensities {
    float ptRevA = 0.f;       ///< z(t−1) sampled from the light side: from y(s−1), or as an emitter's origin (s = 0)
    float ptMinusRevA = 0.f;  ///< z(t−2) sampled from z(t−1) given y(s−1), or emitted from z(t−1) (s = 0)
    float qsRevA = 0.f;       ///< y(s−1) sampled from z(t−1) given z(t−2)
    float qsMinusRevA = 0.f;  ///< y(s−2) sampled from y(s−1) given z(t−1)
    float qsOriginA = 0.f;    ///< s = 1 only: the resampled y0's density as a light sub-path's origin
};

/// The densities of strategy (s, t) evaluated from the vertices (each BSDF built anew); connectBdpt
/// computes the same numbers with the BSDFs it built to evaluate f.
ConnectionDensities connectionDensities(const RenderContext& ctx, std::span<const PathVertex> light,
                                        std::span<const PathVertex> camera, int s, int t, const PathVertex* qs,
                                        const PathVertex* pt);

/// The MIS weight of strategy (s, t) given the connection endpoints actually used: `qs` replaces
/// y(s−1) and `pt` replaces z(t−1) (they differ from the stored ones when resampled, s = 1 or
/// t = 1). Combines the connection's densities with the sub-paths' prefixes in O(1)
/// (bdptMisWeightFromEnds; bdptMisPrefixes must have run on the sub-paths).
float bdptStrategyWeight(const RenderContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                         int s, int t, const PathVertex* qs, const PathVertex* pt, const ConnectionDensities& densities,
                         MisHeuristic heuristic, double eta = 0.0);
/// The same with the densities evaluated by connectionDensities.
float bdptStrategyWeight(const RenderContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                         int s, int t, const PathVertex* qs, const PathVertex* pt, MisHeuristic heuristic, double eta = 0.0);

}  // namespace tessera
