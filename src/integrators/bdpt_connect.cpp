#include "integrators/bdpt_connect.h"

#include <array>

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

/// Fixed-capacity scratch for the MIS densities, growing on the heap only for very long paths.
class MisScratch {
public:
    MisScratch(const MisScratch&) = delete;
    explicit MisScratch(size_t n) : heap_(n > kInline ? n : 0) { data_ = n > kInline ? heap_.data() : inline_.data(); }
    MisVertex& operator[](size_t i) { return data_[i]; }
    MisVertex* data() { return data_; }

private:
    static constexpr size_t kInline = 32;
    std::array<MisVertex, kInline> inline_{};
    std::vector<MisVertex> heap_;
    MisVertex* data_;
};

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

}  // namespace

float bdptStrategyWeight(const RenderContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                         int s, int t, const PathVertex* qs, const PathVertex* pt, MisHeuristic heuristic) {
    // A camera ray that escaped to the environment (z1 at infinity) can only be found by that
    // camera ray: no lens connection reaches a direction.
    if (s == 0 && t == 2 && pt->atInfinity) return 1.f;
    MisScratch y{size_t(s)}, z{size_t(t)};
    // For s = 1 the light sub-path may be empty (its y0 is the resampled `qs`, filled in below).
    for (int i = 0; i < s && size_t(i) < light.size(); ++i)
        y[size_t(i)] = {light[size_t(i)].pdfFwdA, light[size_t(i)].pdfRevA, light[size_t(i)].delta};
    for (int i = 0; i < t; ++i) z[size_t(i)] = {camera[size_t(i)].pdfFwdA, camera[size_t(i)].pdfRevA, camera[size_t(i)].delta};
    const PathVertex* qsMinus = s >= 2 ? &light[size_t(s - 2)] : nullptr;
    const PathVertex* ptMinus = t >= 2 ? &camera[size_t(t - 2)] : nullptr;

    // A resampled light endpoint (s = 1) enters the chain with the light sub-path's origin density
    // like every other strategy's y0; the factor `nee` below turns p_1 into the density next-event
    // estimation actually sampled it with (the visible cone of a sphere light). Russian roulette
    // stays out of the densities: the weights still sum to 1 over the strategies of every path,
    // which is all unbiasedness needs (Veach 1997, §9.2.2, eq. 9.6).
    if (s == 1) y[0] = {pdfLightOriginA(ctx, *qs), 0.f, false};  // pdfRevA: set below (the light sub-path may be empty)
    // The connection's endpoints scatter into the connection through a non-delta lobe, whatever lobe
    // their own walk sampled there (pbrt-v3's MISWeight resets them too); a camera endpoint on an
    // emitter acts as the light vertex y0 of strategy s = 1: never delta either.
    if (s > 0) y[size_t(s - 1)].delta = false;
    z[size_t(t - 1)].delta = false;

    // The four densities the connection changes (pbrt-v3 §16.3.4's "pdfRev" updates):
    // z(t−1) sampled from the light side: from y(s−1) (given y(s−2)), or as an emitter origin.
    z[size_t(t - 1)].pdfRevA = s > 0 ? pdfNextA(ctx, qsMinus, *qs, *pt) : pdfLightOriginA(ctx, *pt);
    // z(t−2) sampled from z(t−1) given y(s−1), or emitted from z(t−1) when it lies on a light.
    if (ptMinus) z[size_t(t - 2)].pdfRevA = s > 0 ? pdfNextA(ctx, qs, *pt, *ptMinus) : pdfLightDirectionA(ctx, *pt, *ptMinus);
    // y(s−1) sampled from z(t−1) given z(t−2); y(s−2) from y(s−1) given z(t−1).
    if (s > 0) y[size_t(s - 1)].pdfRevA = pdfNextA(ctx, ptMinus, *pt, *qs);
    if (qsMinus) y[size_t(s - 2)].pdfRevA = pdfNextA(ctx, pt, *qs, *qsMinus);

    bool lightIsDelta = false;
    float nee = 1.f;  // p_NEE / p_origin of x0 given x1, for the strategy s = 1 of this path
    if (s > 0) {
        const PathVertex& y0 = s == 1 ? *qs : light[0];
        lightIsDelta = ctx.scene.lights().isDelta(y0.lightIndex);  // point, spot, directional: never hit
        nee = neeOverOriginA(ctx, y0, s == 1 ? *pt : light[1]);
    } else if (ptMinus) {
        nee = neeOverOriginA(ctx, *pt, *ptMinus);
    }
    return bdptMisWeight({y.data(), size_t(s)}, {z.data(), size_t(t)}, lightIsDelta, heuristic, nee);
}

ConnectionResult connectBdpt(const RenderContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                             int s, int t, Sampler& sampler, MisHeuristic heuristic, bool computeWeight) {
    ConnectionResult r;
    if (t < 1 || s + t < 2) return r;
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
        r.L = qs->beta * evalVertex(ctx, *qs, *pt, TransportMode::Importance) * G *
              evalVertex(ctx, *pt, *qs, TransportMode::Radiance) * pt->beta;
        if (isBlack(r.L) || !unoccluded(ctx, *qs, *pt)) return ConnectionResult{};
        attenuateEdge(ctx, r.L, *qs, *pt);
    }
    if (isBlack(r.L)) return ConnectionResult{};
    r.weight = computeWeight ? bdptStrategyWeight(ctx, light, camera, s, t, qs, pt, heuristic) : 1.f;
    return r;
}

}  // namespace tessera
