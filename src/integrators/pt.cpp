#include "integrators/pt.h"

#include "integrators/russian_roulette.h"
#include "integrators/sample_trace.h"
#include "integrators/volume.h"
#include "materials/surface_bsdf.h"

namespace tessera {

// Why this estimator is unbiased: the path throughput β is the product of f·|cos θ|/pdf of the
// sampled directions, the Monte Carlo estimator of each term of the path integral (Veach 1997,
// eq. 8.19), and every path that ends on an emitter contributes β·Le exactly once. Russian
// roulette divides by the survival probability (integrators/russian_roulette.h). A segment inside
// an absorbing volume multiplies β by its transmittance (integrators/volume.h): part of f.
Rgb PtIntegrator::sample(const RenderContext& ctx, Vec2i, Vec2f raster, Sampler& sampler, SplatSink&) const {
    const Scene& scene = ctx.scene;
    Ray ray = ctx.camera.generateRay(raster, sampler.get2D());
    Rgb L(0.f), beta(1.f);
    float rrScale = 1.f;  // what Russian roulette looks at (integrators/russian_roulette.h)
    Rgb sigmaLeave(0.f);  // σa of the traced segment as seen from the vertex it left (integrators/volume.h)
    Vec3f prevP = ray.o;
    for (int depth = 0;; ++depth) {
        Hit hit;
        // Camera rays follow their neighbours (tiles in pixel order): the coherent kernel.
        if (!(depth == 0 ? ctx.accel.intersectCoherent(ray, hit) : ctx.accel.intersect(ray, hit))) {
            // An escaping ray sees the environment (zero without one).
            if (scene.lights().hasEnvironment()) {
                attenuateEscape(beta, sigmaLeave);
                L += beta * scene.lights().environmentLe(glm::normalize(ray.d));
            }
            break;
        }
        SurfaceInteraction si = scene.interaction(ray, hit);
        Vec3f wo = -glm::normalize(ray.d);
        const BsdfParams params = scene.bsdfParams(si, ctx.camera.pixelFootprint(si.p));
        // Russian roulette keeps looking at the BSDF weights only (rrScale): a path through index-
        // matched glass stays deterministic, and absorption ends paths by driving β to zero.
        attenuateArrival(beta, sigmaLeave, params, si.ng, wo, si.p, prevP);
        if (si.lightIndex != kInvalidId) L += beta * scene.lights().emitted(si.lightIndex, si.ng, wo, si.bary);
        SampleTrace* trace = ctx.trace;
        if (trace) [[unlikely]] {
            trace->vertex(depth, si.p, si.ng, si.materialId, beta);
            if (si.lightIndex != kInvalidId) trace->add("emissionContribution", beta * scene.lights().emitted(si.lightIndex, si.ng, wo, si.bary));
            trace->add("L", L);
        }
        if (ctx.maxDepth >= 0 && depth >= ctx.maxDepth) break;

        sampler.startBounce(depth);
        SurfaceBsdf bsdf(params, si.ns, si.ng);
        SurfaceBsdfSample bs;
        if (!bsdf.sample(wo, sampler, TransportMode::Radiance, bs)) break;
        if (trace) [[unlikely]] {
            trace->bsdfSample(bs.wiWorld, bs.pdfFwdW, bs.isDelta, bs.weight);
        }
        beta *= bs.weight;
        rrScale *= maxComponent(bs.weight) * bs.eta * bs.eta;
        if (isBlack(beta)) break;
        if (depth >= kRouletteMinDepth && !survivesRoulette(rrScale, beta, sampler, trace)) break;
        ray = spawnRay(si.p, si.ng, bs.wiWorld);
        sigmaLeave = volumeSigmaAt(params, si.ng, bs.wiWorld);
        prevP = si.p;
    }
    return L;
}

}  // namespace tessera
