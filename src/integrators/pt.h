#pragma once
/// \file pt.h
/// `pt`: unidirectional path tracing with BSDF sampling only. Emission is added whenever a path
/// hits an emitter, with weight 1. The simplest unbiased estimator, and the baseline the others
/// are compared with; it cannot see point lights (a ray never hits a delta light).
#include "integrators/integrator.h"

namespace tessera {

class PtIntegrator final : public Integrator {
public:
    std::string_view name() const override { return "pt"; }
    Rgb sample(const RenderContext& ctx, Vec2i pixel, Vec2f raster, Sampler& sampler, SplatSink& splats) const override;
};

}  // namespace tessera
