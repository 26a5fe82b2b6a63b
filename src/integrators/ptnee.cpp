#include "integrators/ptnee.h"

#include "core/sampling.h"
#include "integrators/next_event.h"
#include "integrators/russian_roulette.h"
#include "integrators/sample_trace.h"
#include "integrators/volume.h"
#include "materials/surface_bsdf.h"

namespace tessera {

namespace {

/// Emission found by BSDF sampling at `si`, weighted against the light-sampling strategy that could
/// have produced the same path (`prevPdfW`: the BSDF density that produced the ray from `prevP`).
/// Emission reached through a delta bounce or seen directly from the camera has weight 1.
void addEmission(const RenderContext& ctx, const SurfaceInteraction& si, const Vec3f& wo, const Rgb& beta, bool deltaBounce,
                 float prevPdfW, const Vec3f& prevP, Rgb& L) {
    const LightSet& lights = ctx.scene.lights();
    Rgb Le = lights.emitted(si.lightIndex, si.ng, wo, si.bary);
    if (isBlack(Le)) return;
    SampleTrace* trace = ctx.trace;
    if (deltaBounce) {
        L += beta * Le;
        if (trace) [[unlikely]] {
            trace->add("Le", Le);
            trace->add("emissionMisW", 1.f);
            trace->add("emissionContribution", beta * Le);
        }
        return;
    }
    float pdfLightW = lights.pdfW(si.lightIndex, prevP, si.p, si.ng);
    L += beta * Le * powerHeuristic(prevPdfW, pdfLightW);
    if (trace) [[unlikely]] {
        trace->add("Le", Le);
        trace->add("emissionPdfLightW", pdfLightW);
        trace->add("emissionMisW", powerHeuristic(prevPdfW, pdfLightW));
        trace->add("emissionContribution", beta * Le * powerHeuristic(prevPdfW, pdfLightW));
    }
}

/// Next-event estimation at a non-delta vertex: one light sample (integrators/next_event.h),
/// weighted against BSDF sampling, added to L. `params` (the BSDF's inputs at si) and the emitter's
/// material decide whether the shadow segment runs inside an absorbing volume (integrators/volume.h).
void addLightSample(const RenderContext& ctx, const SurfaceInteraction& si, const BsdfParams& params, const SurfaceBsdf& bsdf,
                    const Vec3f& wo, const Rgb& beta, Sampler& sampler, Rgb& L) {
    NextEventSample ne;
    if (!sampleNextEvent(ctx.scene.lights(), si.p, si.ng, wo, sampler, ne)) return;
    const LightSample& ls = ne.light;
    const Vec3f wi = ls.wi;
    SampleTrace* trace = ctx.trace;
    if (trace) [[unlikely]] {
        // Recomputing the BSDF density draws no random numbers: the path is unchanged.
        trace->add("lightP", ls.p);
        trace->add("lightPdfW", ls.pdfW);
        if (!ls.isDelta) trace->add("lightBsdfPdfW", bsdf.pdfFwdW(wo, wi));
    }
    // Which side of the geometric surface wi may leave on (reflection or transmission) is the BSDF's
    // side rule, inside evalWithPdf (Veach 1997, §5.3).
    float bsdfPdfW;
    Rgb f = bsdf.evalWithPdf(wo, wi, TransportMode::Radiance, bsdfPdfW) * std::abs(glm::dot(wi, bsdf.ns()));
    if (isBlack(f) || !lightVisible(ctx.accel, si.p, si.ng, ls)) return;
    // The shadow segment inside a volume: tested at both ends, as the traced ray to the same light
    // point would be (integrators/volume.h).
    if (Rgb sigmaHere = volumeSigmaAt(params, si.ng, wi), sigmaLight = emitterVolumeSigma(ctx.scene, ls.index, ls.n, -wi);
        segmentAttenuates(sigmaHere, sigmaLight))
        f *= segmentTransmittance(sigmaHere, sigmaLight, ls.isInfinite ? kInfiniteSegment : glm::length(ls.p - si.p));
    // A delta light (point, spot, directional) cannot be hit by BSDF sampling: light sampling is its
    // only strategy.
    float w = ls.isDelta ? 1.f : powerHeuristic(ls.pdfW, bsdfPdfW);
    L += beta * f * ls.Le * (w / ls.pdfW);
    if (trace) [[unlikely]] {
        trace->add("lightMisW", w);
        trace->add("lightContribution", beta * f * ls.Le * (w / ls.pdfW));
    }
}

/// The environment reached by a BSDF-sampled ray that escaped: weighted against sampling the
/// environment directly (its importance-sampled direction density at the previous vertex).
void addEscapedEnvironment(const RenderContext& ctx, const Vec3f& wLight, const Rgb& beta, bool deltaBounce, float prevPdfW,
                           Rgb& L) {
    const LightSet& lights = ctx.scene.lights();
    Rgb Le = lights.environmentLe(wLight);
    if (isBlack(Le)) return;
    float w = deltaBounce ? 1.f : powerHeuristic(prevPdfW, lights.environmentPdfW(wLight));
    L += beta * Le * w;
    if (SampleTrace* trace = ctx.trace) [[unlikely]] {
        trace->add("environmentLe", Le);
        trace->add("emissionMisW", w);
        trace->add("emissionContribution", beta * Le * w);
    }
}

}  // namespace

// Why this estimator is unbiased (writeup, "Light transport and why each estimator is unbiased"):
//  * Each path vertex contributes emission through two strategies: a light sample (NEE) and a BSDF
//    sample that happens to hit the emitter. Their MIS weights (power heuristic, Veach 1997 eq. 9.13)
//    sum to 1 for every light path both can produce, so the combination is unbiased (Veach eq. 9.9
//    with the weights' partition of unity, Theorem 9.2). Emission reached through a delta bounce
//    (mirror, glass) or seen directly from the camera can only come from BSDF sampling: weight 1.
//    The environment is one more emitter: an escaping BSDF ray finds it, light sampling picks its
//    directions by luminance; delta lights (point, spot, directional) only light sampling finds.
//  * Throughput β is the product of f·|cos|/pdf of the sampled directions: the standard
//    Monte Carlo estimator of the path-integral terms (Veach 1997 eq. 8.19). A segment inside an
//    absorbing volume multiplies β (traced) or the light sample (shadow segment) by the same
//    transmittance (integrators/volume.h): part of f, so both strategies still share one integrand.
//  * Russian roulette divides β by the survival probability (integrators/russian_roulette.h).
Rgb PtNeeIntegrator::sample(const RenderContext& ctx, Vec2i, Vec2f raster, Sampler& sampler, SplatSink&) const {
    const Scene& scene = ctx.scene;
    Ray ray = ctx.camera.generateRay(raster, sampler.get2D());

    Rgb L(0.f), beta(1.f);
    float etaScale = 1.f;        // product of η² over refractions: Russian roulette looks at β·etaScale
    bool deltaBounce = true;     // the previous vertex was the camera or a delta BSDF
    float prevPdfW = 0.f;        // solid-angle density of the BSDF sample that produced `ray`
    Vec3f prevP = ray.o;
    Vec3f prevSurfaceP = ray.o;  // the previous vertex itself (prevP is offset off its surface)
    Rgb sigmaLeave(0.f);         // σa of the traced segment as seen from the vertex it left (integrators/volume.h)

    for (int depth = 0;; ++depth) {
        Hit hit;
        // Camera rays follow their neighbours (tiles in pixel order): the coherent kernel.
        if (!(depth == 0 ? ctx.accel.intersectCoherent(ray, hit) : ctx.accel.intersect(ray, hit))) {
            if (scene.lights().hasEnvironment()) {
                attenuateEscape(beta, sigmaLeave);
                addEscapedEnvironment(ctx, glm::normalize(ray.d), beta, deltaBounce, prevPdfW, L);
            }
            break;
        }
        SurfaceInteraction si = scene.interaction(ray, hit);
        Vec3f wo = -glm::normalize(ray.d);
        const BsdfParams params = scene.bsdfParams(si, ctx.camera.pixelFootprint(si.p));
        attenuateArrival(beta, sigmaLeave, params, si.ng, wo, si.p, prevSurfaceP);
        SampleTrace* trace = ctx.trace;
        if (trace) [[unlikely]] {
            trace->vertex(depth, si.p, si.ng, si.materialId, beta);
        }
        if (si.lightIndex != kInvalidId) addEmission(ctx, si, wo, beta, deltaBounce, prevPdfW, prevP, L);
        if (ctx.maxDepth >= 0 && depth >= ctx.maxDepth) break;

        sampler.startBounce(depth);
        SurfaceBsdf bsdf(params, si.ns, si.ng);
        if (!bsdf.isDelta()) addLightSample(ctx, si, params, bsdf, wo, beta, sampler, L);

        // Continue the path by BSDF sampling.
        SurfaceBsdfSample bs;
        if (!bsdf.sample(wo, sampler, TransportMode::Radiance, bs)) {
            if (trace) [[unlikely]] trace->add("L", L);
            break;
        }
        if (trace) [[unlikely]] {
            trace->bsdfSample(bs.wiWorld, bs.pdfFwdW, bs.isDelta, bs.weight);
            trace->add("L", L);
        }
        beta *= bs.weight;
        etaScale *= bs.eta * bs.eta;
        deltaBounce = bs.isDelta;
        prevPdfW = bs.pdfFwdW;
        if (isBlack(beta)) break;
        if (depth >= kRouletteMinDepth && !survivesThroughputRoulette(maxComponent(beta) * etaScale, beta, sampler, trace)) break;
        ray = spawnRay(si.p, si.ng, bs.wiWorld);
        prevP = ray.o;
        prevSurfaceP = si.p;
        sigmaLeave = volumeSigmaAt(params, si.ng, bs.wiWorld);
    }
    return L;
}

}  // namespace tessera
