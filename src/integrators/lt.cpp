#include "integrators/lt.h"

#include "integrators/bdpt_connect.h"
#include "integrators/sample_trace.h"

namespace tessera {

// Why this estimator is unbiased: a light sub-path y0 … y(s−1) is sampled with density
// p(y0) Π p(y_i | y_{i−1}); its throughput α_L (PathVertex::beta) is Le·G·f… divided by those
// densities (Veach 1997, eq. 10.5). Connecting y(s−1) to a lens point sampled with density pdfW
// (solid angle at y(s−1)) multiplies by f(y(s−1)) · |cos| · We / pdfW: the contribution
// f(path)/p(path) of the measurement integral for the pixel the lens ray lands on (Veach eq. 8.7
// with importance We of camera.h). The film divides splats by samples per pixel: each camera sample
// traces one light path, so a pixel receives (W·H·spp) paths whose We is normalised over the whole
// film: We·(W·H) per pixel, divided by W·H·spp paths = 1/spp per splat. Paths whose camera-side
// vertex is delta (seen through a mirror or glass) cannot be connected and are missed.
// The environment seen directly is the one path no light sub-path can reach (its vertex lies at
// infinity, so no lens connection ends there): a camera ray finds it (BDPT's s = 0, t = 2 strategy,
// the only strategy for these paths, so it needs no weight).
Rgb LtIntegrator::sample(const RenderContext& ctx, Vec2i, Vec2f raster, Sampler& sampler, SplatSink& splats) const {
    thread_local std::vector<PathVertex> light;
    int maxVertices = ctx.maxDepth < 0 ? -1 : ctx.maxDepth + 1;
    traceLightSubpath(ctx, sampler, maxVertices, light);
    if (ctx.trace) [[unlikely]] traceSubpath(*ctx.trace, "light vertex", light);
    for (int s = 1; s <= int(light.size()); ++s) {
        ConnectionResult r = connectBdpt(ctx, light, {}, s, /* t = */ 1, sampler, MisHeuristic::Power, /* computeWeight = */ false);
        if (ctx.trace) [[unlikely]] {
            // Light tracing has one strategy per light vertex (t = 1): no MIS weight.
            ctx.trace->begin("strategy", s, 1);
            ctx.trace->add("contribution", r.L);
            ctx.trace->add("raster", Vec3f(r.raster.x, r.raster.y, 0.f));
        }
        if (!isBlack(r.L)) splats.splat(ctx.camera.width(), ctx.camera.height(), r.raster, r.L);
    }
    const LightSet& lights = ctx.scene.lights();
    if (!lights.hasEnvironment()) return Rgb(0.f);  // no random numbers drawn: scenes without one are unchanged
    sampler.startLens();
    Ray ray = ctx.camera.generateRay(raster, sampler.get2D());
    Hit hit;
    if (ctx.accel.intersectCoherent(ray, hit)) return Rgb(0.f);
    Rgb Le = lights.environmentLe(glm::normalize(ray.d));
    if (ctx.trace) [[unlikely]] ctx.trace->add("environmentSeenDirectly", Le);
    return Le;
}

}  // namespace tessera
