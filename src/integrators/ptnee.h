#pragma once
/// \file ptnee.h
/// `ptnee`: unidirectional path tracing with next-event estimation and multiple importance sampling
/// (power heuristic) between light sampling and BSDF sampling, Russian roulette termination.
#include "integrators/integrator.h"

namespace tessera {

class PtNeeIntegrator final : public Integrator {
public:
    std::string_view name() const override { return "ptnee"; }
    Rgb sample(const RenderContext& ctx, Vec2i pixel, Vec2f raster, Sampler& sampler, SplatSink& splats) const override;
};

}  // namespace tessera
