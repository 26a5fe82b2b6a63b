#include "integrators/pt.h"

#include "integrators/russian_roulette.h"
#include "integrators/sample_trace.h"
#include "materials/surface_bsdf.h"

namespace tessera {

// Why this estimator is unbiased: the path throughput β is the product of f·|cos θ|/pdf of the
// sampled directions, the Monte Carlo estimator of each term of the path integral (Veach 1997,
// eq. 8.19), and every path that ends on an emitter contributes β·Le exactly once. Russian
// roulette divides by the survival probability (integrators/russian_roulette.h).
Rgb PtIntegrator::sample(const RenderContext& ctx, Vec2i, Vec2f raster, Sampler& sampler, SplatSink&) const {
    const Scene& scene = ctx.scene;
    Ray ray = ctx.camera.generateRay(raster, sampler.get2D());
    Rgb L(0.f), beta(1.f);
    float rrScale = 1.f;  // what Russian roulette looks at (integrators/russian_roulette.h)
    for (int depth = 0;; ++depth) {
        Hit hit;
        // Camera rays follow their neighbours (tiles in pixel order): the coherent kernel.
        if (!(depth == 0 ? ctx.accel.intersectCoherent(ray, hit) : ctx.accel.intersect(ray, hit))) break;
        SurfaceInteraction si = scene.interaction(ray, hit);
        Vec3f wo = -glm::normalize(ray.d);
        if (si.lightIndex != kInvalidId) L += beta * scene.lights().emitted(si.lightIndex, si.ng, wo);
        SampleTrace* trace = ctx.trace;
        if (trace) [[unlikely]] {
            trace->vertex(depth, si.p, si.ng, si.materialId, beta);
            if (si.lightIndex != kInvalidId) trace->add("emissionContribution", beta * scene.lights().emitted(si.lightIndex, si.ng, wo));
            trace->add("L", L);
        }
        if (ctx.maxDepth >= 0 && depth >= ctx.maxDepth) break;

        SurfaceBsdf bsdf(scene.bsdfParams(si, ctx.camera.pixelFootprint(si.p)), si.ns, si.ng);
        SurfaceBsdfSample bs;
        float uLobe = sampler.get1D();
        Vec2f uDir = sampler.get2D();
        if (!bsdf.sample(wo, uLobe, uDir, TransportMode::Radiance, bs)) break;
        if (trace) [[unlikely]] {
            trace->bsdfSample(bs.wiWorld, bs.pdfFwdW, bs.isDelta, bs.weight);
        }
        beta *= bs.weight;
        rrScale *= maxComponent(bs.weight) * bs.eta * bs.eta;
        if (isBlack(beta)) break;
        if (depth >= kRouletteMinDepth && !survivesRoulette(rrScale, beta, sampler, trace)) break;
        ray = spawnRay(si.p, si.ng, bs.wiWorld);
    }
    return L;
}

}  // namespace tessera
