#pragma once
/// \file bdpt.h
/// `bdpt`: Veach's bidirectional path tracing (Veach 1997, ch. 10) with every strategy (s, t):
/// s = 0 (camera path hits a light), s = 1 (light resampled from the camera vertex), t = 1 (light
/// vertex connected to the lens, splatted) and all general connections, combined by multiple
/// importance sampling (power heuristic by default, balance selectable). Russian roulette ends both
/// sub-paths; ctx.maxDepth (bounces) bounds s + t − 2 when set.
#include "integrators/bdpt_mis.h"
#include "integrators/integrator.h"

namespace tessera {

struct BdptSettings {
    MisHeuristic heuristic = MisHeuristic::Power;  ///< β = 2 (Veach eq. 9.13); Balance: β = 1
    /// Debug view (pbrt's visualizestrategies): keep only strategy (onlyS, onlyT); −1 = all. All
    /// strategies are still evaluated, so random numbers are consumed exactly as in a full render and
    /// the weighted strategy images sum to the full image.
    int onlyS = -1, onlyT = -1;
    bool unweighted = false;  ///< contributions without their MIS weight (debug view only)
};

class BdptIntegrator final : public Integrator {
public:
    explicit BdptIntegrator(BdptSettings settings = {}) : settings_(settings) {}
    std::string_view name() const override { return "bdpt"; }
    Rgb sample(const RenderContext& ctx, Vec2i pixel, Vec2f raster, Sampler& sampler, SplatSink& splats) const override;

private:
    BdptSettings settings_;
};

}  // namespace tessera
