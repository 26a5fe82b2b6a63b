#pragma once
/// \file bdpt.h
/// `bdpt`: Veach's bidirectional path tracing (Veach 1997, ch. 10) with every strategy (s, t):
/// s = 0 (camera path hits a light), s = 1 (light resampled from the camera vertex), t = 1 (light
/// vertex connected to the lens, splatted) and all general connections, combined by multiple
/// importance sampling (power heuristic by default, balance selectable). Russian roulette ends both
/// sub-paths; ctx.maxDepth (bounces) bounds s + t − 2 when set.
#include <span>

#include "integrators/bdpt_mis.h"
#include "integrators/integrator.h"
#include "integrators/path_vertex.h"

namespace tessera {

struct BdptSettings {
    MisHeuristic heuristic = MisHeuristic::Power;  ///< β = 2 (Veach eq. 9.13); Balance: β = 1
    /// Debug view (pbrt's visualizestrategies): keep only strategy (onlyS, onlyT); −1 = all. All
    /// strategies are still evaluated, so random numbers are consumed exactly as in a full render and
    /// the weighted strategy images sum to the full image.
    int onlyS = -1, onlyT = -1;
    bool unweighted = false;  ///< contributions without their MIS weight (debug view only)
};

/// One sample's camera sub-path through `raster` and light sub-path (at most ctx.maxDepth bounces
/// between them), their MIS prefixes (bdpt_mis.h's (‡) with `eta`; 0 for bdpt) and, when replaying
/// a sample, their trace: what bdpt and vcm draw before connecting.
void traceBdptSubpaths(const RenderContext& ctx, Vec2f raster, Sampler& sampler, MisHeuristic heuristic, double eta,
                       std::vector<PathVertex>& camera, std::vector<PathVertex>& light);

/// Every connection strategy (s, t) of one sample's sub-paths (bdptMisPrefixes must have run on
/// them with the same `eta`): returns the camera pixel's share and splats the t = 1 strategies.
/// `eta` > 0 weights them against VCM's merges too (bdpt_mis.h's (‡)).
Rgb connectAllStrategies(const RenderContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                         Sampler& sampler, SplatSink& splats, const BdptSettings& settings, double eta = 0.0);

class BdptIntegrator final : public Integrator {
public:
    explicit BdptIntegrator(BdptSettings settings = {}) : settings_(settings) {}
    std::string_view name() const override { return "bdpt"; }
    Rgb sample(const RenderContext& ctx, Vec2i pixel, Vec2f raster, Sampler& sampler, SplatSink& splats) const override;

private:
    BdptSettings settings_;
};

}  // namespace tessera
