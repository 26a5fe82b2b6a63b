#pragma once
/// \file lt.h
/// `lt`: light tracing (particle tracing). Each camera sample traces one light sub-path and connects
/// every vertex of it, the light point included, to a point on the lens; the contributions are
/// splatted to the pixels they land on (BDPT's t = 1 strategies alone, all with weight 1).
/// Cannot render what the camera sees only via a delta BSDF (mirrors, glass seen directly).
#include "integrators/integrator.h"

namespace tessera {

class LtIntegrator final : public Integrator {
public:
    std::string_view name() const override { return "lt"; }
    Rgb sample(const RenderContext& ctx, Vec2i pixel, Vec2f raster, Sampler& sampler, SplatSink& splats) const override;
};

}  // namespace tessera
