#include "integrators/path_tracer.h"

#include "core/frame.h"
#include "core/sampling.h"
#include "integrators/sample_trace.h"
#include "materials/bsdf.h"

namespace tessera {

// Why this estimator is unbiased (writeup.md, "Why PT + NEE + MIS is unbiased"):
//  * Each path vertex contributes emission through two strategies: a light sample (NEE) and a BSDF
//    sample that happens to hit the emitter. Their MIS weights (power heuristic, Veach 1997 eq. 9.13)
//    sum to 1 for every light path both can produce, so the combination is unbiased (Veach eq. 9.9
//    with the weights' partition of unity, Theorem 9.2). Emission reached through a delta bounce
//    (mirror, glass) or seen directly from the camera can only come from BSDF sampling: weight 1.
//  * Throughput β is the product of f·|cos|/pdf of the sampled directions: the standard
//    Monte Carlo estimator of the path-integral terms (Veach 1997 eq. 8.19).
//  * Russian roulette continues with probability p = min(1, max β) and divides β by p, so the
//    expected contribution is unchanged (Arvo & Kirk 1990); since p > 0 whenever β ≠ 0, no path with
//    non-zero contribution has zero probability.
Rgb PathTracer::sample(const RenderContext& ctx, Vec2i, Vec2f raster, Sampler& sampler, SplatSink&) const {
    const Scene& scene = ctx.scene;
    const LightSet& lights = scene.lights();
    Ray ray = ctx.camera.generateRay(raster, sampler.get2D());

    Rgb L(0.f), beta(1.f);
    float etaScale = 1.f;        // product of η² over refractions: Russian roulette looks at β·etaScale
    bool deltaBounce = true;     // the previous vertex was the camera or a delta BSDF
    float prevPdfW = 0.f;        // solid-angle density of the BSDF sample that produced `ray`
    Vec3f prevP = ray.o;

    for (int depth = 0;; ++depth) {
        Hit hit;
        // Camera rays follow their neighbours (tiles in pixel order): the coherent kernel.
        if (!(depth == 0 ? ctx.accel.intersectCoherent(ray, hit) : ctx.accel.intersect(ray, hit))) break;
        SurfaceInteraction si = scene.interaction(ray, hit);
        Vec3f wo = -glm::normalize(ray.d);
        SampleTrace* trace = ctx.trace;
        if (trace) [[unlikely]] {
            trace->vertex(depth, si.p, si.ng, si.materialId, beta);
        }

        // Emission found by BSDF sampling, weighted against the light-sampling strategy.
        if (si.lightIndex != kInvalidId) {
            Rgb Le = lights.emitted(si.lightIndex, si.ng, wo);
            if (!isBlack(Le)) {
                if (deltaBounce) {
                    L += beta * Le;
                    if (trace) [[unlikely]] {
                        trace->add("Le", Le);
                        trace->add("emissionMisW", 1.f);
                        trace->add("emissionContribution", beta * Le);
                    }
                } else {
                    float pdfLightW = lights.pdfW(si.lightIndex, prevP, si.p, si.ng);
                    L += beta * Le * powerHeuristic(prevPdfW, pdfLightW);
                    if (trace) [[unlikely]] {
                        trace->add("Le", Le);
                        trace->add("emissionPdfLightW", pdfLightW);
                        trace->add("emissionMisW", powerHeuristic(prevPdfW, pdfLightW));
                        trace->add("emissionContribution", beta * Le * powerHeuristic(prevPdfW, pdfLightW));
                    }
                }
            }
        }
        if (ctx.maxDepth >= 0 && depth >= ctx.maxDepth) break;

        const Material& mat = scene.materials[si.materialId];
        Frame frame(si.ns);
        Vec3f woL = frame.toLocal(wo);
        float woNg = glm::dot(wo, si.ng);
        // Light sampling and MIS densities are evaluated from the point offset off the surface on
        // wo's side (where reflected rays start), not from the surface point itself: for a point on
        // an emitting sphere, "inside or outside the sphere" must not be decided by rounding.
        Vec3f pRef = offsetRayOrigin(si.p, woNg >= 0.f ? si.ng : -si.ng);

        // Next-event estimation: one light sample, weighted against BSDF sampling.
        if (!isDeltaMaterial(mat) && !lights.empty()) {
            LightSample ls;
            float uPick = sampler.get1D();
            Vec2f uLight = sampler.get2D();
            if (lights.sample(pRef, uPick, uLight, ls) && !isBlack(ls.Le)) {
                Vec3f toLight = ls.p - pRef;
                float dist = glm::length(toLight);
                Vec3f wi = toLight / dist;
                Vec3f wiL = frame.toLocal(wi);
                if (trace) [[unlikely]] {
                    // Recomputing the BSDF density draws no random numbers: the path is unchanged.
                    trace->add("lightP", ls.p);
                    trace->add("lightPdfW", ls.pdfW);
                    if (!ls.isDelta) trace->add("lightBsdfPdfW", pdfBsdfW(mat, woL, wiL));
                }
                // Reflection-only BSDFs: wi must leave on wo's side of the *geometric* surface, or a
                // shading normal would let light through (Veach 1997, §5.3).
                if (dist > 0.f && glm::dot(wi, si.ng) * woNg > 0.f) {
                    Rgb f = evalBsdf(mat, woL, wiL, TransportMode::Radiance) * std::abs(wiL.z);
                    if (!isBlack(f) && !ctx.accel.occluded(spawnShadowRay(si.p, si.ng, ls.p, ls.n))) {
                        // A point light cannot be hit by BSDF sampling: light sampling is its only strategy.
                        float w = ls.isDelta ? 1.f : powerHeuristic(ls.pdfW, pdfBsdfW(mat, woL, wiL));
                        L += beta * f * ls.Le * (w / ls.pdfW);
                        if (trace) [[unlikely]] {
                            trace->add("lightMisW", w);
                            trace->add("lightContribution", beta * f * ls.Le * (w / ls.pdfW));
                        }
                    }
                }
            }
        }

        // Continue the path by BSDF sampling.
        BsdfSample bs;
        float uLobe = sampler.get1D();
        Vec2f uDir = sampler.get2D();
        if (!sampleBsdf(mat, woL, uLobe, uDir, TransportMode::Radiance, bs)) {
            if (trace) [[unlikely]] trace->add("L", L);
            break;
        }
        Vec3f wi = frame.toWorld(bs.wiLocal);
        if (trace) [[unlikely]] {
            trace->bsdfSample(wi, bs.pdfW, bs.isDelta, bs.weight);
            trace->add("L", L);
        }
        bool reflected = bs.wiLocal.z * woL.z > 0.f;
        if (reflected != (glm::dot(wi, si.ng) * woNg > 0.f)) break;  // shading/geometric side mismatch
        beta *= bs.weight;
        etaScale *= bs.eta * bs.eta;
        deltaBounce = bs.isDelta;
        prevPdfW = bs.pdfW;
        if (isBlack(beta)) break;

        // Russian roulette (Arvo & Kirk 1990) after two bounces; etaScale keeps paths inside glass
        // from being killed for a radiance scaling that reverses when they leave (pbrt-v4 §14.1.5).
        float rr = maxComponent(beta) * etaScale;
        if (depth >= 2 && rr < 1.f) {
            float q = std::max(0.f, 1.f - rr);
            if (trace) [[unlikely]] trace->add("rrSurvival", 1.f - q);
            if (sampler.get1D() < q) break;
            beta /= 1.f - q;
        }
        ray = spawnRay(si.p, si.ng, wi);
        prevP = ray.o;
    }
    return L;
}

}  // namespace tessera
