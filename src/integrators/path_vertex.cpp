#include "integrators/path_vertex.h"

#include "integrators/russian_roulette.h"

namespace tessera {

float convertDensity(float pdfW, const PathVertex& from, const PathVertex& to) {
    Vec3f w = to.p - from.p;
    float dist2 = glm::dot(w, w);
    if (!(dist2 > 0.f)) return 0.f;
    float pdfA = pdfW / dist2;
    if (to.onSurface()) pdfA *= std::abs(glm::dot(to.ng, w)) / std::sqrt(dist2);
    return pdfA;
}

float pdfNextA(const RenderContext& ctx, const PathVertex* prev, const PathVertex& cur, const PathVertex& next) {
    Vec3f wi = next.p - cur.p;
    float len = glm::length(wi);
    if (!(len > 0.f)) return 0.f;
    wi /= len;
    float pdfW = 0.f;
    switch (cur.type) {
    case VertexType::Camera: {
        float pdfPosA;
        ctx.camera.pdfEmission(wi, pdfPosA, pdfW);
        break;
    }
    case VertexType::Light:
        return pdfLightDirectionA(ctx, cur, next);
    case VertexType::Surface: {
        if (!prev) return 0.f;
        SurfaceBsdf bsdf(cur.bsdf, cur.ns, cur.ng);
        Vec3f wo = glm::normalize(prev->p - cur.p);
        pdfW = bsdf.pdfFwdW(wo, wi);
        break;
    }
    }
    return convertDensity(pdfW, cur, next);
}

float pdfLightOriginA(const RenderContext& ctx, const PathVertex& v) {
    if (v.lightIndex == kInvalidId) return 0.f;
    float pdfPosA, pdfDirW;
    ctx.scene.lights().pdfEmission(v.lightIndex, v.ng, v.ng, pdfPosA, pdfDirW);
    return pdfPosA;
}

float pdfLightDirectionA(const RenderContext& ctx, const PathVertex& v, const PathVertex& next) {
    if (v.lightIndex == kInvalidId) return 0.f;
    Vec3f w = next.p - v.p;
    float len = glm::length(w);
    if (!(len > 0.f)) return 0.f;
    float pdfPosA, pdfDirW;
    ctx.scene.lights().pdfEmission(v.lightIndex, v.ng, w / len, pdfPosA, pdfDirW);
    return convertDensity(pdfDirW, v, next);
}

Rgb evalVertex(const RenderContext& ctx, const PathVertex& v, const PathVertex& next, TransportMode mode) {
    Vec3f w = next.p - v.p;
    float len = glm::length(w);
    if (!(len > 0.f)) return Rgb(0.f);
    w /= len;
    switch (v.type) {
    case VertexType::Camera:
        return Rgb(ctx.camera.importance(v.p, w));
    case VertexType::Light: {
        const LightSet& lights = ctx.scene.lights();
        if (lights.isDeltaPosition(v.lightIndex)) return lights.light(v.lightIndex).Le;  // intensity
        return lights.emitted(v.lightIndex, v.ng, w);
    }
    case VertexType::Surface: {
        SurfaceBsdf bsdf(v.bsdf, v.ns, v.ng);
        return bsdf.eval(v.woWorld, w, mode);
    }
    }
    return Rgb(0.f);
}

Rgb emittedAt(const RenderContext& ctx, const PathVertex& v) {
    if (v.type != VertexType::Surface || v.lightIndex == kInvalidId) return Rgb(0.f);
    return ctx.scene.lights().emitted(v.lightIndex, v.ng, v.woWorld);
}

namespace {

/// Extends a sub-path whose last vertex is `out.back()` along `ray` (Veach 1997, §10.2: each
/// vertex sampled from its predecessor with the local density, converted to area). `beta` is the
/// throughput carried by the ray.
void randomWalk(const RenderContext& ctx, Ray ray, Rgb beta, Sampler& sampler, TransportMode mode,
                int maxVertices, std::vector<PathVertex>& out) {
    const Scene& scene = ctx.scene;
    float rrScale = 1.f;  // product of BSDF weights (and η² for radiance): what Russian roulette looks at
    int limit = maxVertices < 0 ? kMaxSubpathVertices : std::min(maxVertices, kMaxSubpathVertices);
    while (int(out.size()) < limit) {
        Hit hit;
        // The camera ray (a camera subpath's first segment) follows its neighbours: the coherent kernel.
        bool cameraRay = mode == TransportMode::Radiance && out.size() == 1;
        if (!(cameraRay ? ctx.accel.intersectCoherent(ray, hit) : ctx.accel.intersect(ray, hit))) break;
        SurfaceInteraction si = scene.interaction(ray, hit);
        PathVertex v;
        v.type = VertexType::Surface;
        v.p = si.p;
        v.ng = si.ng;
        v.ns = si.ns;
        v.woWorld = -glm::normalize(ray.d);
        v.beta = beta;
        v.bsdf = scene.bsdfParams(si, ctx.camera.pixelFootprint(si.p));
        v.lightIndex = si.lightIndex;
        // Densities are evaluated from the vertex positions rather than taken from the sampling
        // routine: the connection code evaluates them the same way, so every strategy sees exactly
        // the same p→/p← for a vertex and the weights sum to one to rounding (grazing cosine-
        // hemisphere samples otherwise differ by a few percent). Delta densities stay 0.
        const size_t n = out.size();
        const PathVertex& prev = out[n - 1];
        v.pdfFwdA = prev.delta ? 0.f : pdfNextA(ctx, n >= 2 ? &out[n - 2] : nullptr, prev, v);
        // The successor now exists: the density of the predecessor's predecessor being sampled
        // from `prev` given `v` (Veach's p←), i.e. pdfRevA of out[n − 2].
        if (n >= 2) out[n - 2].pdfRevA = prev.delta ? 0.f : pdfNextA(ctx, &v, prev, out[n - 2]);
        out.push_back(v);
        if (int(out.size()) >= limit) break;

        PathVertex& cur = out.back();
        SurfaceBsdf bsdf(cur.bsdf, cur.ns, cur.ng);
        SurfaceBsdfSample bs;
        float uLobe = sampler.get1D();
        Vec2f uDir = sampler.get2D();
        if (!bsdf.sample(cur.woWorld, uLobe, uDir, mode, bs)) break;
        cur.delta = bs.isDelta;
        beta *= bs.weight;
        rrScale *= maxComponent(bs.weight) * (mode == TransportMode::Radiance ? bs.eta * bs.eta : 1.f);
        if (isBlack(beta)) break;
        // Russian roulette from the third vertex on (integrators/russian_roulette.h).
        if (out.size() >= 3 && !survivesRoulette(rrScale, beta, sampler, /* trace = */ nullptr)) break;
        ray = spawnRay(cur.p, cur.ng, bs.wiWorld);
    }
}

}  // namespace

void traceCameraSubpath(const RenderContext& ctx, Vec2f raster, Sampler& sampler, int maxVertices, std::vector<PathVertex>& out) {
    out.clear();
    if (maxVertices == 0) return;
    Ray ray = ctx.camera.generateRay(raster, sampler.get2D());
    PathVertex z0;
    z0.type = VertexType::Camera;
    z0.p = ray.o;
    z0.ng = z0.ns = ctx.camera.forward();
    // Box-filtered pixel: We cos / (pdfPosA pdfDirW) = 1 for the pixel the ray was generated in.
    z0.beta = Rgb(1.f);
    float pdfPosA, pdfDirW;
    ctx.camera.pdfEmission(ray.d, pdfPosA, pdfDirW);
    z0.pdfFwdA = pdfPosA;  // never used by the weights (no strategy hits the lens)
    out.push_back(z0);
    randomWalk(ctx, ray, Rgb(1.f), sampler, TransportMode::Radiance, maxVertices, out);
}

void traceLightSubpath(const RenderContext& ctx, Sampler& sampler, int maxVertices, std::vector<PathVertex>& out) {
    out.clear();
    const LightSet& lights = ctx.scene.lights();
    if (maxVertices == 0 || lights.empty()) return;
    float uPick = sampler.get1D();
    Vec2f uPos = sampler.get2D();
    Vec2f uDir = sampler.get2D();
    LightEmission le;
    if (!lights.sampleEmission(uPick, uPos, uDir, le) || isBlack(le.Le)) return;
    PathVertex y0;
    y0.type = VertexType::Light;
    y0.p = le.p;
    y0.ng = y0.ns = le.n;
    y0.lightIndex = le.index;
    // y0 carries 1/pdfPosA; its "f" towards the next vertex is the emitted radiance (intensity).
    y0.beta = Rgb(1.f / le.pdfPosA);
    y0.pdfFwdA = le.pdfPosA;
    out.push_back(y0);
    float cosLight = le.isDeltaPos ? 1.f : std::abs(glm::dot(le.n, le.dir));
    Rgb beta = le.Le * (cosLight / (le.pdfPosA * le.pdfDirW));
    Ray ray = le.isDeltaPos ? Ray{le.p, le.dir, 0.f, kInfinity} : spawnRay(le.p, le.n, le.dir);
    randomWalk(ctx, ray, beta, sampler, TransportMode::Importance, maxVertices, out);
}

}  // namespace tessera
