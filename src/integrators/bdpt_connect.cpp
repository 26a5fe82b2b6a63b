#include "integrators/bdpt_connect.h"

#include "integrators/next_event.h"

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

/// p_NEE(x0 | x1) / p_origin(x0), both area densities at x0 (bdpt_mis.h, `neeOverOriginA`): next-event
/// estimation from x1 samples a sphere light over the cone it subtends (LightSet::sampleOne), a light
/// sub-path starts uniformly on its area. Triangle, punctual and infinite lights are sampled alike
/// both ways (ratio 1). The reference point is offset off x1 towards x0, as next_event.h offsets it
/// towards the side the light is sampled from: a function of the two vertices only, so every
/// strategy of a path computes the same factor.
float neeOverOriginA(const RenderContext& ctx, const PathVertex& x0, const PathVertex& x1) {
    if (x0.lightIndex == kInvalidId || x0.atInfinity || x1.type != VertexType::Surface) return 1.f;
    const LightSet& lights = ctx.scene.lights();
    if (lights.light(x0.lightIndex).type != LightType::Sphere) return 1.f;
    Vec3f d = x0.p - x1.p;
    float dist2 = glm::dot(d, d);
    if (!(dist2 > 0.f)) return 1.f;
    Vec3f pRef = offsetRayOrigin(x1.p, glm::dot(d, x1.ng) >= 0.f ? x1.ng : -x1.ng);
    float neeA = lights.pdfW(x0.lightIndex, pRef, x0.p, x0.ng) * std::abs(glm::dot(x0.ng, d)) / (dist2 * std::sqrt(dist2));
    float originA = pdfLightOriginA(ctx, x0);
    return neeA > 0.f && originA > 0.f ? neeA / originA : 1.f;
}

MisVertex misVertexOf(const PathVertex& v) { return {v.pdfFwdA, v.pdfRevA, v.delta}; }

}  // namespace

void bdptMisPrefixes(const RenderContext& ctx, std::span<PathVertex> light, std::span<PathVertex> camera, MisHeuristic heuristic) {
    // M_j of bdpt_mis.h's (†), in each sub-path's sampling order. The light side's c_0 needs y0
    // hittable (not a delta light) and its g_1 is strategy s = 1's factor at y1; the lens has no
    // strategy (c_0 = 0, M_0 = 0).
    double prefix = 0.0;
    if (!light.empty()) {
        const bool lightIsDelta = ctx.scene.lights().isDelta(light[0].lightIndex);
        const double g1 = light.size() >= 2 ? misNeeFactor(neeOverOriginA(ctx, light[0], light[1]), heuristic) : 1.0;
        for (size_t j = 0; j < light.size(); ++j) {
            bool prevDelta = j > 0 ? light[j - 1].delta : lightIsDelta;
            prefix = misPrefixStep(prefix, misVertexOf(light[j]), !light[j].delta && !prevDelta, j == 1 ? g1 : 1.0, heuristic);
            light[j].misPrefix = prefix;
        }
    }
    prefix = 0.0;
    for (size_t j = 0; j < camera.size(); ++j) {
        if (j > 0) prefix = misPrefixStep(prefix, misVertexOf(camera[j]), !camera[j].delta && !camera[j - 1].delta, 1.0, heuristic);
        camera[j].misPrefix = prefix;
    }
}

float bdptStrategyWeight(const RenderContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                         int s, int t, const PathVertex* qs, const PathVertex* pt, MisHeuristic heuristic) {
    // A camera ray that escaped to the environment (z1 at infinity) can only be found by that
    // camera ray: no lens connection reaches a direction.
    if (s == 0 && t == 2 && pt->atInfinity) return 1.f;
    const PathVertex* qsMinus = s >= 2 ? &light[size_t(s - 2)] : nullptr;
    const PathVertex* ptMinus = t >= 2 ? &camera[size_t(t - 2)] : nullptr;
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
    if (s == 1) y.end = {pdfLightOriginA(ctx, *qs), 0.f, false};  // pdfRevA: set below (the light sub-path may be empty)
    else if (s >= 2) y.end = misVertexOf(*qs);
    if (qsMinus) y.next = misVertexOf(*qsMinus);
    y.prefix = s >= 3 ? light[size_t(s - 3)].misPrefix : 0.0;
    y.nextPrevDelta = s >= 3 ? light[size_t(s - 3)].delta : lightIsDelta;
    z.end = misVertexOf(*pt);
    if (ptMinus) z.next = misVertexOf(*ptMinus);
    z.prefix = t >= 3 ? camera[size_t(t - 3)].misPrefix : 0.0;
    z.nextPrevDelta = t >= 3 && camera[size_t(t - 3)].delta;
    // The connection's endpoints scatter into the connection through a non-delta lobe, whatever lobe
    // their own walk sampled there (pbrt-v3's MISWeight resets them too); a camera endpoint on an
    // emitter acts as the light vertex y0 of strategy s = 1: never delta either.
    y.end.delta = false;
    z.end.delta = false;

    // The four densities the connection changes (pbrt-v3 §16.3.4's "pdfRev" updates):
    // z(t−1) sampled from the light side: from y(s−1) (given y(s−2)), or as an emitter origin;
    // y(s−2) sampled from y(s−1) given z(t−1) (the same vertex pair: one call for both).
    if (s == 0) z.end.pdfRevA = pdfLightOriginA(ctx, *pt);
    else if (qsMinus) pdfBothWaysA(ctx, *qsMinus, *qs, *pt, z.end.pdfRevA, y.next.pdfRevA);
    else z.end.pdfRevA = pdfNextA(ctx, nullptr, *qs, *pt);
    // y(s−1) sampled from z(t−1) given z(t−2); z(t−2) sampled from z(t−1) given y(s−1), or emitted
    // from z(t−1) when it lies on a light.
    if (s == 0) {
        if (ptMinus) z.next.pdfRevA = pdfLightDirectionA(ctx, *pt, *ptMinus);
    } else if (ptMinus) {
        pdfBothWaysA(ctx, *ptMinus, *pt, *qs, y.end.pdfRevA, z.next.pdfRevA);
    } else {
        y.end.pdfRevA = pdfNextA(ctx, nullptr, *pt, *qs);
    }

    float nee = 1.f;  // p_NEE / p_origin of x0 given x1, for the strategy s = 1 of this path
    if (s > 0) nee = neeOverOriginA(ctx, s == 1 ? *qs : light[0], s == 1 ? *pt : light[1]);
    else if (ptMinus) nee = neeOverOriginA(ctx, *pt, *ptMinus);
    return bdptMisWeightFromEnds(y, z, lightIsDelta, heuristic, nee);
}

ConnectionResult connectBdpt(const RenderContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                             int s, int t, Sampler& sampler, MisHeuristic heuristic, bool computeWeight) {
    ConnectionResult r;
    if (t < 1 || s + t < 2) return r;
    sampler.startConnection(s, t);
    PathVertex sampled;  // the resampled endpoint for s = 1 or t = 1
    // For s = 1 the light point is resampled below: the light sub-path may even be empty.
    const PathVertex* qs = s > 0 && size_t(s) <= light.size() ? &light[size_t(s - 1)] : nullptr;
    const PathVertex* pt = &camera.data()[t - 1];  // not dereferenced when t = 1 (replaced below)

    if (s == 0) {
        // The camera sub-path found an emitter: C = α_E · Le (Veach eq. 10.8 with s = 0).
        r.L = pt->beta * emittedAt(ctx, *pt);
    } else if (t == 1) {
        // Light tracing: connect y(s−1) to a lens point; the contribution lands on another pixel.
        if (!qs || !qs->connectible()) return r;
        CameraSample cs;
        if (!ctx.camera.sampleIncoming(qs->p, sampler.get2D(), cs)) return r;
        sampled.type = VertexType::Camera;
        sampled.p = cs.pLens;
        sampled.ng = sampled.ns = ctx.camera.forward();
        sampled.beta = Rgb(cs.We / cs.pdfW);
        Rgb f = evalVertex(ctx, *qs, sampled, TransportMode::Importance);
        r.L = qs->beta * f * sampled.beta * cosAt(*qs, cs.wiWorld);
        if (isBlack(r.L) || !unoccluded(ctx, *qs, sampled)) return ConnectionResult{};
        attenuateEdge(ctx, r.L, *qs, sampled);
        r.raster = cs.raster;
        pt = &sampled;
    } else if (s == 1) {
        // Next-event estimation: resample the light point from z(t−1), exactly as ptnee samples it
        // (integrators/next_event.h).
        NextEventSample ne;
        if (!pt->connectible() || !sampleNextEvent(ctx.scene.lights(), pt->p, pt->ng, pt->woWorld, sampler, ne)) return r;
        const LightSample& ls = ne.light;
        sampled.type = VertexType::Light;
        sampled.p = ls.p;
        sampled.atInfinity = ls.isInfinite;
        sampled.ng = sampled.ns = ls.isInfinite ? ls.wi : ls.n;
        sampled.lightIndex = ls.index;
        sampled.bary = ls.bary;
        // Radiance (area, environment), I/d² (point, spot) or E (directional) over the NEE density.
        sampled.beta = ls.Le / ls.pdfW;
        Rgb f = evalVertex(ctx, *pt, sampled, TransportMode::Radiance);
        r.L = pt->beta * f * sampled.beta * cosAt(*pt, ls.wi);
        if (isBlack(r.L) || !lightVisible(ctx.accel, pt->p, pt->ng, ls)) return ConnectionResult{};
        attenuateEdge(ctx, r.L, *pt, sampled);
        qs = &sampled;
    } else {
        // General connection (Veach eq. 10.8): α_L · f(y) · G · f(z) · α_E.
        if (!qs->connectible() || !pt->connectible()) return r;
        Vec3f w = pt->p - qs->p;
        float dist2 = glm::dot(w, w);
        if (!(dist2 > 0.f)) return r;
        Vec3f wn = w / std::sqrt(dist2);
        float G = cosAt(*qs, wn) * cosAt(*pt, wn) / dist2;
        r.L = qs->beta * evalVertexTowards(ctx, *qs, wn, TransportMode::Importance) * G *
              evalVertexTowards(ctx, *pt, -wn, TransportMode::Radiance) * pt->beta;
        if (isBlack(r.L) || !unoccluded(ctx, *qs, *pt)) return ConnectionResult{};
        attenuateEdge(ctx, r.L, *qs, *pt);
    }
    if (isBlack(r.L)) return ConnectionResult{};
    r.weight = computeWeight ? bdptStrategyWeight(ctx, light, camera, s, t, qs, pt, heuristic) : 1.f;
    return r;
}

}  // namespace tessera
