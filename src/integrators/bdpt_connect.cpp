#include "integrators/bdpt_connect.h"

#include "integrators/bdpt.h"
#include "integrators/next_event.h"
#include "integrators/sample_trace.h"

namespace tessera {
namespace {

/// |cos| between a unit direction and the vertex's shading normal; 1 off surfaces (point light).
/// Shading normals here pair with the shading correction inside evalVertex (Veach 1997, §5.3).
float cosAt(const PathVertex& v, const Vec3f& w) { return v.onSurface() ? std::abs(glm::dot(v.ns, w)) : 1.f; }

bool unoccluded(const RenderContext& ctx, const PathVertex& a, const PathVertex& b) {
    return !ctx.accel.occluded(spawnShadowRay(a.p, a.offsetNormal(), b.p, b.offsetNormal()));
}

/// Multiplies a connection's contribution by the Beer–Lambert transmittance of its edge a–b, the
/// same rule (path_vertex.h, integrators/volume.h) the random walks applied to their own segments:
/// every strategy that builds a path sees the same f, so the MIS weights stay a partition of unity.
void attenuateEdge(const RenderContext& ctx, Rgb& L, const PathVertex& a, const PathVertex& b) {
    bool attenuates;
    Rgb T = segmentTransmittance(ctx, a, b, attenuates);
    if (attenuates) L *= T;
}

/// neeOverOriginA (below) for x0 on a sphere light.
float sphereNeeOverOriginA(const RenderContext& ctx, const PathVertex& x0, const PathVertex& x1) {
    const LightSet& lights = ctx.scene.lights();
    Vec3f d = x0.p - x1.p;
    float dist2 = glm::dot(d, d);
    if (!(dist2 > 0.f)) return 1.f;
    Vec3f pRef = offsetRayOrigin(x1.p, glm::dot(d, x1.ng) >= 0.f ? x1.ng : -x1.ng);
    float neeA = lights.pdfW(x0.lightIndex, pRef, x0.p, x0.ng) * std::abs(glm::dot(x0.ng, d)) / (dist2 * std::sqrt(dist2));
    float originA = pdfLightOriginA(ctx, x0);
    return neeA > 0.f && originA > 0.f ? neeA / originA : 1.f;
}

/// p_NEE(x0 | x1) / p_origin(x0), both area densities at x0 (bdpt_mis.h, `neeOverOriginA`): next-event
/// estimation from x1 samples a sphere light over the cone it subtends (LightSet::sampleOne), a light
/// sub-path starts uniformly on its area. Triangle, punctual and infinite lights are sampled alike
/// both ways (ratio 1). The reference point is offset off x1 towards x0, as next_event.h offsets it
/// towards the side the light is sampled from: a function of the two vertices only, so every
/// strategy of a path computes the same factor.
/// Every weight asks: the tests inline, the sphere's case out of line.
inline float neeOverOriginA(const RenderContext& ctx, const PathVertex& x0, const PathVertex& x1) {
    if (x0.lightIndex == kInvalidId || x0.atInfinity || x1.type != VertexType::Surface) return 1.f;
    if (ctx.scene.lights().light(x0.lightIndex).type != LightType::Sphere) return 1.f;
    return sphereNeeOverOriginA(ctx, x0, x1);
}

MisVertex misVertexOf(const PathVertex& v) { return {v.pdfFwdA, v.pdfRevA, v.delta}; }

}  // namespace

double bdptLightNeeFactor(const RenderContext& ctx, std::span<const PathVertex> light, MisHeuristic heuristic) {
    return light.size() >= 2 ? misNeeFactor(neeOverOriginA(ctx, light[0], light[1]), heuristic) : 1.0;
}

void bdptMisPrefixes(const RenderContext& ctx, std::span<PathVertex> light, std::span<PathVertex> camera, MisHeuristic heuristic,
                     double eta) {
    // M_j of bdpt_mis.h's (‡), in each sub-path's sampling order. The light side's c_0 needs y0
    // hittable (not a delta light) and its g_1 is strategy s = 1's factor at y1; the lens has no
    // strategy (c_0 = 0, M_0 = 0). Merges (η > 0) happen at every vertex after the first that the
    // path leaves through a non-delta lobe.
    double prefix = 0.0;
    if (!light.empty()) {
        const bool lightIsDelta = ctx.scene.lights().isDelta(light[0].lightIndex);
        const double g1 = bdptLightNeeFactor(ctx, light, heuristic);
        for (size_t j = 0; j < light.size(); ++j) {
            bool prevDelta = j > 0 ? light[j - 1].delta : lightIsDelta;
            const double mu = misMergeTerm(j >= 1 && !light[j].delta, light[j].pdfFwdA, eta, heuristic);
            prefix = misPrefixStep(prefix, misVertexOf(light[j]), !light[j].delta && !prevDelta, j == 1 ? g1 : 1.0, heuristic, mu);
            light[j].misPrefix = prefix;
        }
    }
    prefix = 0.0;
    for (size_t j = 0; j < camera.size(); ++j) {
        if (j > 0) {
            const double mu = misMergeTerm(!camera[j].delta && !camera[j].atInfinity, camera[j].pdfFwdA, eta, heuristic);
            prefix = misPrefixStep(prefix, misVertexOf(camera[j]), !camera[j].delta && !camera[j - 1].delta, 1.0, heuristic, mu);
        }
        camera[j].misPrefix = prefix;
    }
}

ConnectionDensities connectionDensities(const RenderContext& ctx, std::span<const PathVertex> light,
                                        std::span<const PathVertex> camera, int s, int t, const PathVertex* qs,
                                        const PathVertex* pt) {
    ConnectionDensities d;
    const PathVertex* qsMinus = s >= 2 ? &light[size_t(s - 2)] : nullptr;
    const PathVertex* ptMinus = t >= 2 ? &camera[size_t(t - 2)] : nullptr;
    // z(t−1) sampled from the light side: from y(s−1) (given y(s−2)), or as an emitter origin;
    // y(s−2) sampled from y(s−1) given z(t−1) (the same vertex pair: one call for both).
    if (s == 0) {
        // z(t−2) emitted from z(t−1), which lies on a light.
        if (ptMinus) pdfLightBothA(ctx, *pt, *ptMinus, d.ptRevA, d.ptMinusRevA);
        else d.ptRevA = pdfLightOriginA(ctx, *pt);
        return d;
    }
    if (qsMinus) pdfBothWaysA(ctx, *qsMinus, *qs, *pt, d.ptRevA, d.qsMinusRevA);
    else pdfLightBothA(ctx, *qs, *pt, d.qsOriginA, d.ptRevA);  // s = 1: y0 itself, emitting towards z(t−1)
    // y(s−1) sampled from z(t−1) given z(t−2); z(t−2) sampled from z(t−1) given y(s−1).
    if (ptMinus) pdfBothWaysA(ctx, *ptMinus, *pt, *qs, d.qsRevA, d.ptMinusRevA);
    else d.qsRevA = pdfNextA(ctx, nullptr, *pt, *qs);
    return d;
}

float bdptStrategyWeight(const RenderContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                         int s, int t, const PathVertex* qs, const PathVertex* pt, MisHeuristic heuristic, double eta) {
    return bdptStrategyWeight(ctx, light, camera, s, t, qs, pt, connectionDensities(ctx, light, camera, s, t, qs, pt), heuristic, eta);
}

namespace {

/// bdptStrategyWeight's body, inlined into the connections below (each strategy's weight paid a
/// call with ten arguments).
[[gnu::always_inline]] inline float strategyWeight(const RenderContext& ctx, std::span<const PathVertex> light,
                                                   std::span<const PathVertex> camera, int s, int t, const PathVertex* qs,
                                                   const PathVertex* pt, const ConnectionDensities& d, MisHeuristic heuristic,
                                                   double eta) {
    // A camera ray that escaped to the environment (z1 at infinity) can only be found by that
    // camera ray: no lens connection reaches a direction.
    if (s == 0 && t == 2 && pt->atInfinity) return 1.f;
    const bool lightIsDelta = s > 0 && ctx.scene.lights().isDelta((s == 1 ? *qs : light[0]).lightIndex);  // never hit
    // Only the two last vertices of each side change with the connection; the rest enters through
    // the prefix M of the third vertex from the end (bdpt_mis.h).
    MisEnds y, z;
    y.n = s;
    z.n = t;
    // A resampled light endpoint (s = 1) enters the chain with the light sub-path's origin density
    // like every other strategy's y0; the factor `nee` below turns p_1 into the density next-event
    // estimation actually sampled it with (the visible cone of a sphere light). Russian roulette
    // stays out of the densities: the weights still sum to 1 over the strategies of every path,
    // which is all unbiasedness needs (Veach 1997, §9.2.2, eq. 9.6).
    if (s == 1) y.end.pdfFwdA = d.qsOriginA;
    else if (s >= 2) y.end = misVertexOf(*qs);
    if (s >= 2) y.next = misVertexOf(light[size_t(s - 2)]);
    y.prefix = s >= 3 ? light[size_t(s - 3)].misPrefix : 0.0;
    y.nextPrevDelta = s >= 3 ? light[size_t(s - 3)].delta : lightIsDelta;
    z.end = misVertexOf(*pt);
    if (t >= 2) z.next = misVertexOf(camera[size_t(t - 2)]);
    z.prefix = t >= 3 ? camera[size_t(t - 3)].misPrefix : 0.0;
    z.nextPrevDelta = t >= 3 && camera[size_t(t - 3)].delta;
    // The connection's endpoints scatter into the connection through a non-delta lobe, whatever lobe
    // their own walk sampled there (pbrt-v3's MISWeight resets them too); a camera endpoint on an
    // emitter acts as the light vertex y0 of strategy s = 1: never delta either.
    y.end.delta = false;
    z.end.delta = false;
    // The four densities the connection changes (pbrt-v3 §16.3.4's "pdfRev" updates).
    z.end.pdfRevA = d.ptRevA;
    if (t >= 2) z.next.pdfRevA = d.ptMinusRevA;
    if (s >= 1) y.end.pdfRevA = d.qsRevA;
    if (s >= 2) y.next.pdfRevA = d.qsMinusRevA;

    // VCM (η > 0): merges at the interior vertices next to the connection, (‡) of bdpt_mis.h. The
    // connection's ends scatter through a non-delta lobe; y0, the lens and a camera end that is
    // the light's own point (s = 0) are no interior vertices.
    if (eta > 0.0) {
        y.endMerges = s >= 2;
        y.nextMerges = s >= 3 && !light[size_t(s - 2)].delta;
        z.endMerges = s >= 1 && t >= 2;
        z.nextMerges = t >= 3 && !camera[size_t(t - 2)].delta;
    }
    float nee = 1.f;  // p_NEE / p_origin of x0 given x1, for the strategy s = 1 of this path
    if (s > 0) nee = neeOverOriginA(ctx, s == 1 ? *qs : light[0], s == 1 ? *pt : light[1]);
    else if (t >= 2) nee = neeOverOriginA(ctx, *pt, camera[size_t(t - 2)]);
    return bdptMisWeightFromEnds(y, z, lightIsDelta, heuristic, nee, eta);
}

}  // namespace

float bdptStrategyWeight(const RenderContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                         int s, int t, const PathVertex* qs, const PathVertex* pt, const ConnectionDensities& d,
                         MisHeuristic heuristic, double eta) {
    return strategyWeight(ctx, light, camera, s, t, qs, pt, d, heuristic, eta);
}

namespace {

// The strategies below have one caller, connectBdpt, and are inlined into it: a dozen connections
// per sample each paid a second call with a dozen arguments (spans spill to the stack) on top of
// connectBdpt's own.

/// s = 0: the camera sub-path found an emitter at z(t−1): C = α_E · Le (Veach eq. 10.8 with s = 0).
ConnectionResult connectEmitterHit(const RenderContext& ctx, std::span<const PathVertex> camera, int t, MisHeuristic heuristic,
                                   bool computeWeight, double eta) {
    const PathVertex& pt = camera[size_t(t - 1)];
    ConnectionResult r;
    r.L = pt.beta * emittedAt(ctx, pt);
    if (isBlack(r.L)) return ConnectionResult{};
    r.weight = computeWeight ? bdptStrategyWeight(ctx, {}, camera, 0, t, nullptr, &pt, heuristic, eta) : 1.f;
    return r;
}

/// t = 1 (light tracing): y(s−1) joined to a resampled lens point; the contribution lands on
/// another pixel.
[[gnu::always_inline]] inline ConnectionResult connectLens(const RenderContext& ctx, std::span<const PathVertex> light, int s, Sampler& sampler,
                             MisHeuristic heuristic, bool computeWeight, double eta) {
    ConnectionResult r;
    if (size_t(s) > light.size()) return r;
    const PathVertex& qs = light[size_t(s - 1)];
    if (!qs.connectible()) return r;
    CameraSample cs;
    // A pinhole has a single lens point: its draw is skipped rather than computed (the draws after
    // it, and so the image, stay the same).
    Vec2f uLens(0.5f);
    if (ctx.camera.isPinhole()) sampler.skip2D();
    else uLens = sampler.get2D();
    if (!ctx.camera.sampleIncoming(qs.p, uLens, cs)) return r;
    // Only the lens vertex's position, axis and weight change between connections: one vertex per
    // thread, whose other fields keep their defaults, spares building a whole (mostly surface) vertex.
    thread_local PathVertex lens = [] {
        PathVertex v;
        v.type = VertexType::Camera;
        return v;
    }();
    lens.p = cs.pLens;
    lens.ng = lens.ns = ctx.camera.forward();
    lens.beta = Rgb(cs.We / cs.pdfW);
    const Vec3f& w = cs.wiWorld;  // directionTo(qs, lens), bit for bit: the same difference over its length
    // A surface end's BSDF serves f here and the two densities of its weight (built once; for a
    // light vertex, s = 1, it is a Lambertian stand-in that nothing reads).
    const bool surface = qs.type == VertexType::Surface;
    const SurfaceBsdf bsdf(qs.bsdf, qs.ns, qs.ng, SurfaceBsdf::Use::EvalOnly);
    Rgb f = surface ? bsdf.eval(qs.woWorld, w, TransportMode::Importance) : evalVertexTowards(ctx, qs, w, TransportMode::Importance);
    r.L = qs.beta * f * lens.beta * cosAt(qs, cs.wiWorld);
    if (isBlack(r.L) || !unoccluded(ctx, qs, lens)) return ConnectionResult{};
    attenuateEdge(ctx, r.L, qs, lens);
    if (isBlack(r.L)) return ConnectionResult{};
    r.raster = cs.raster;
    r.weight = 1.f;
    if (computeWeight) {
        ConnectionDensities d;
        if (surface && s >= 2) {
            pdfBothWaysA(ctx, bsdf, light[size_t(s - 2)], qs, lens, d.ptRevA, d.qsMinusRevA);
            d.qsRevA = pdfNextA(ctx, nullptr, lens, qs);
        } else {
            d = connectionDensities(ctx, light, {&lens, 1}, s, 1, &qs, &lens);
        }
        r.weight = strategyWeight(ctx, light, {&lens, 1}, s, 1, &qs, &lens, d, heuristic, eta);
    }
    return r;
}

/// s = 1 (next-event estimation): a light point resampled from z(t−1), exactly as ptnee samples it
/// (integrators/next_event.h).
[[gnu::always_inline]] inline ConnectionResult connectLight(const RenderContext& ctx, std::span<const PathVertex> camera, int t, Sampler& sampler,
                              MisHeuristic heuristic, bool computeWeight, double eta) {
    ConnectionResult r;
    const PathVertex& pt = camera[size_t(t - 1)];
    NextEventSample ne;
    if (!pt.connectible() || !sampleNextEvent(ctx.scene.lights(), pt.p, pt.ng, pt.woWorld, sampler, ne)) return r;
    const LightSample& ls = ne.light;
    // One light vertex per thread, as connectLens's lens vertex: every field that differs between
    // light samples is set here, the others keep their defaults.
    thread_local PathVertex y0 = [] {
        PathVertex v;
        v.type = VertexType::Light;
        return v;
    }();
    y0.p = ls.p;
    y0.atInfinity = ls.isInfinite;
    y0.ng = y0.ns = ls.isInfinite ? ls.wi : ls.n;
    y0.lightIndex = ls.index;
    y0.bary = ls.bary;
    // Radiance (area, environment), I/d² (point, spot) or E (directional) over the NEE density.
    y0.beta = ls.Le / ls.pdfW;
    const Vec3f w = directionTo(pt, y0);
    if (w == Vec3f(0.f)) return r;
    // z(t−1) is a surface (connectible, t ≥ 2): its BSDF serves f and its two densities.
    SurfaceBsdf bsdf(pt.bsdf, pt.ns, pt.ng, SurfaceBsdf::Use::EvalOnly);
    r.L = pt.beta * bsdf.eval(pt.woWorld, w, TransportMode::Radiance) * y0.beta * cosAt(pt, ls.wi);
    if (isBlack(r.L) || !lightVisible(ctx.accel, pt.p, pt.ng, ls)) return ConnectionResult{};
    attenuateEdge(ctx, r.L, pt, y0);
    if (isBlack(r.L)) return ConnectionResult{};
    r.weight = 1.f;
    if (computeWeight) {
        ConnectionDensities d;
        pdfLightBothA(ctx, y0, pt, d.qsOriginA, d.ptRevA);
        pdfBothWaysA(ctx, bsdf, camera[size_t(t - 2)], pt, y0, d.qsRevA, d.ptMinusRevA);
        r.weight = strategyWeight(ctx, {}, camera, 1, t, &y0, &pt, d, heuristic, eta);
    }
    return r;
}

/// General connection (Veach eq. 10.8): α_L · f(y(s−1)) · G · f(z(t−1)) · α_E, both ends surfaces
/// (s ≥ 2 and t ≥ 2: every vertex after a sub-path's first is one).
[[gnu::always_inline]] inline ConnectionResult connectVertices(const RenderContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                                 int s, int t, MisHeuristic heuristic, bool computeWeight, double eta) {
    ConnectionResult r;
    const PathVertex& qs = light[size_t(s - 1)];
    const PathVertex& pt = camera[size_t(t - 1)];
    if (!qs.connectible() || !pt.connectible()) return r;
    Vec3f w = pt.p - qs.p;
    float dist2 = glm::dot(w, w);
    if (!(dist2 > 0.f)) return r;
    Vec3f wn = w / std::sqrt(dist2);
    float G = cosAt(qs, wn) * cosAt(pt, wn) / dist2;
    // Each end's BSDF is built once: f here, and the two densities of the weight below. A third of
    // these connections leave an end on a side its BSDF does not scatter to: the other is skipped.
    SurfaceBsdf bsdfPt(pt.bsdf, pt.ns, pt.ng, SurfaceBsdf::Use::EvalOnly);
    Rgb fPt = bsdfPt.eval(pt.woWorld, -wn, TransportMode::Radiance);
    if (isBlack(fPt)) return r;
    SurfaceBsdf bsdfQs(qs.bsdf, qs.ns, qs.ng, SurfaceBsdf::Use::EvalOnly);
    r.L = qs.beta * bsdfQs.eval(qs.woWorld, wn, TransportMode::Importance) * G * fPt * pt.beta;
    if (isBlack(r.L) || !unoccluded(ctx, qs, pt)) return ConnectionResult{};
    attenuateEdge(ctx, r.L, qs, pt);
    if (isBlack(r.L)) return ConnectionResult{};
    r.weight = 1.f;
    if (computeWeight) {
        ConnectionDensities d;
        pdfBothWaysA(ctx, bsdfQs, light[size_t(s - 2)], qs, pt, d.ptRevA, d.qsMinusRevA);
        pdfBothWaysA(ctx, bsdfPt, camera[size_t(t - 2)], pt, qs, d.qsRevA, d.ptMinusRevA);
        r.weight = strategyWeight(ctx, light, camera, s, t, &qs, &pt, d, heuristic, eta);
    }
    return r;
}

/// connectBdpt's body: inlined into it and into connectAllStrategies' loop (a dozen calls per
/// sample each paid the call and its nine arguments).
[[gnu::always_inline]] inline ConnectionResult connectStrategy(const RenderContext& ctx, std::span<const PathVertex> light,
                                                                std::span<const PathVertex> camera, int s, int t, Sampler& sampler,
                                                                MisHeuristic heuristic, bool computeWeight, double eta) {
    if (t < 1 || s + t < 2) return {};
    if (s == 0) return connectEmitterHit(ctx, camera, t, heuristic, computeWeight, eta);
    // Only the resampling strategies draw numbers: each from its own block of the sampler.
    if (s == 1 || t == 1) sampler.startConnection(s, t);
    if (t == 1) return connectLens(ctx, light, s, sampler, heuristic, computeWeight, eta);
    // For s = 1 the light point is resampled: the light sub-path may even be empty.
    if (s == 1) return connectLight(ctx, camera.first(size_t(t)), t, sampler, heuristic, computeWeight, eta);
    return connectVertices(ctx, light, camera, s, t, heuristic, computeWeight, eta);
}

}  // namespace

ConnectionResult connectBdpt(const RenderContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                             int s, int t, Sampler& sampler, MisHeuristic heuristic, bool computeWeight, double eta) {
    return connectStrategy(ctx, light, camera, s, t, sampler, heuristic, computeWeight, eta);
}

Rgb connectAllStrategies(const RenderContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                         Sampler& sampler, SplatSink& splats, const BdptSettings& settings, double eta) {
    const int maxDepth = ctx.maxDepth;
    Rgb L(0.f);
    const int nCamera = int(camera.size()), nLight = int(light.size());
    for (int t = 1; t <= nCamera; ++t) {
        // s = 1 resamples its light point, so it exists even when the light sub-path is empty (its
        // origin emitted nothing: a black texel of an emissive texture); leaving it out would drop
        // the next-event strategy for those samples while its weight still counts on it. (1, 1)
        // joins the light sub-path's own y0 to the lens; s + t − 2 bounces at most maxDepth.
        int sMax = t == 1 ? nLight : std::max(nLight, 1);
        if (maxDepth >= 0) sMax = std::min(sMax, maxDepth + 2 - t);
        // s = 0 needs z(t−1) on an emitter (and t ≥ 2): most camera vertices are not, and the
        // strategy is then zero without a call (the trace still lists every strategy).
        const int sMin = t >= 2 && (camera[size_t(t - 1)].lightIndex != kInvalidId || ctx.trace) ? 0 : 1;
        for (int s = sMin; s <= sMax; ++s) {
            ConnectionResult r = connectStrategy(ctx, light, camera, s, t, sampler, settings.heuristic, true, eta);
            if (ctx.trace) [[unlikely]] {
                // Unweighted C*_{s,t}, its MIS weight and what reaches the image (t = 1: a splat).
                ctx.trace->begin("strategy", s, t);
                ctx.trace->add("unweighted", r.L);
                ctx.trace->add("misW", r.weight);
                ctx.trace->add("contribution", r.L * r.weight);
                if (t == 1) ctx.trace->add("raster", Vec3f(r.raster.x, r.raster.y, 0.f));
            }
            if (isBlack(r.L)) continue;
            if ((settings.onlyS >= 0 && s != settings.onlyS) || (settings.onlyT >= 0 && t != settings.onlyT)) continue;
            Rgb c = settings.unweighted ? r.L : r.L * r.weight;
            if (t == 1) splats.splat(ctx.camera.width(), ctx.camera.height(), r.raster, c);
            else L += c;
        }
    }
    return L;
}

}  // namespace tessera
