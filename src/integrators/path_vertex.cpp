#include "integrators/path_vertex.h"

#include <optional>

#include "integrators/russian_roulette.h"
#include "integrators/volume.h"

namespace tessera {

float convertDensity(float pdfW, const PathVertex& from, const PathVertex& to) {
    if (to.atInfinity) return pdfW;  // a direction has no area: densities towards it stay in solid angle
    Vec3f w = to.p - from.p;
    float dist2 = glm::dot(w, w);
    if (!(dist2 > 0.f)) return 0.f;
    float pdfA = pdfW / dist2;
    if (to.onSurface()) pdfA *= std::abs(glm::dot(to.ng, w)) / std::sqrt(dist2);
    return pdfA;
}

float pdfNextA(const RenderContext& ctx, const PathVertex* prev, const PathVertex& cur, const PathVertex& next) {
    Vec3f wi = directionTo(cur, next);
    if (wi == Vec3f(0.f)) return 0.f;
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
        SurfaceBsdf bsdf(cur.bsdf, cur.ns, cur.ng, SurfaceBsdf::Use::EvalOnly);
        Vec3f wo = directionTo(cur, *prev);
        pdfW = bsdf.pdfFwdW(wo, wi);
        break;
    }
    }
    return convertDensity(pdfW, cur, next);
}

namespace {

/// The segment from `from` to `to` as the densities use it: squared length, length and unit
/// direction (one home for the arithmetic the walk caches in PathVertex::toPrev).
void segmentBetween(const Vec3f& from, const Vec3f& to, float& dist2, float& len, Vec3f& dir) {
    Vec3f d = to - from;
    dist2 = glm::dot(d, d);
    len = std::sqrt(dist2);
    dir = d / len;
}

}  // namespace

void pdfBothWaysA(const RenderContext& ctx, const PathVertex& pred, const PathVertex& cur, const PathVertex& b, float& pdfToBA,
                  float& pdfToPredA) {
    if (cur.type != VertexType::Surface) {
        pdfToBA = pdfNextA(ctx, &pred, cur, b);
        pdfToPredA = pdfNextA(ctx, &b, cur, pred);
        return;
    }
    pdfBothWaysA(ctx, SurfaceBsdf(cur.bsdf, cur.ns, cur.ng, SurfaceBsdf::Use::EvalOnly), pred, cur, b, pdfToBA, pdfToPredA);
}

void pdfBothWaysA(const RenderContext& ctx, const SurfaceBsdf& bsdfAtCur, const PathVertex& pred, const PathVertex& cur,
                  const PathVertex& b, float& pdfToBA, float& pdfToPredA) {
    // The same directions, frame, side test and BSDF inputs serve both densities: one SurfaceBsdf,
    // and each segment's length computed once for its direction and its solid-angle-to-area factor
    // (the segment to the predecessor once per vertex, by the walk: PathVertex::toPrev). The
    // arithmetic is that of directionTo and convertDensity, so the densities are bit-identical to
    // two pdfNextA calls. Vertices at infinity and coincident points take the general route.
    Vec3f db = b.p - cur.p, da = pred.p - cur.p;
    float dist2B = glm::dot(db, db), dist2Pred, lenPred;
    Vec3f toPred;
    if (cur.toPrevLen > 0.f && cur.prevP == pred.p) {
        dist2Pred = cur.toPrevDist2;
        lenPred = cur.toPrevLen;
        toPred = cur.toPrev;
    } else {
        segmentBetween(cur.p, pred.p, dist2Pred, lenPred, toPred);
    }
    if (pred.atInfinity || b.atInfinity || !(dist2Pred > 0.f) || !(dist2B > 0.f)) {
        pdfToBA = pdfNextA(ctx, &pred, cur, b);
        pdfToPredA = pdfNextA(ctx, &b, cur, pred);
        return;
    }
    float lenB = std::sqrt(dist2B);
    float pdfToBW, pdfToPredW;
    bsdfAtCur.pdfBothW(toPred, db / lenB, pdfToBW, pdfToPredW);
    pdfToBA = pdfToBW / dist2B;
    if (b.onSurface()) pdfToBA *= std::abs(glm::dot(b.ng, db)) / lenB;
    pdfToPredA = pdfToPredW / dist2Pred;
    if (pred.onSurface()) pdfToPredA *= std::abs(glm::dot(pred.ng, da)) / lenPred;
}

float pdfLightOriginA(const RenderContext& ctx, const PathVertex& v) {
    if (v.lightIndex == kInvalidId) return 0.f;
    float pdfPosA, pdfDirW;
    if (v.atInfinity) {
        // The direction is the infinite light's "origin" (pbrt-v3 §16.3.1, InfiniteLightDensity).
        ctx.scene.lights().pdfEmission(v.lightIndex, Vec3f(0.f), -v.ng, pdfPosA, pdfDirW);
        return pdfDirW;
    }
    ctx.scene.lights().pdfEmission(v.lightIndex, v.ng, v.ng, pdfPosA, pdfDirW);
    return pdfPosA;
}

float pdfLightDirectionA(const RenderContext& ctx, const PathVertex& v, const PathVertex& next) {
    if (v.lightIndex == kInvalidId || next.atInfinity) return 0.f;
    const LightSet& lights = ctx.scene.lights();
    if (v.atInfinity) {
        // The origin on the emission disk, seen at `next` through the cosine there: parallel rays
        // have no 1/d² (pbrt-v3 §16.3.1, Vertex::PdfLight).
        float pdfA = lights.diskPdfA();
        return next.onSurface() ? pdfA * std::abs(glm::dot(next.ng, v.ng)) : pdfA;
    }
    Vec3f w = directionTo(v, next);
    if (w == Vec3f(0.f)) return 0.f;
    float pdfPosA, pdfDirW;
    lights.pdfEmission(v.lightIndex, v.ng, w, pdfPosA, pdfDirW);
    return convertDensity(pdfDirW, v, next);
}

void pdfLightBothA(const RenderContext& ctx, const PathVertex& v, const PathVertex& next, float& originA, float& towardsNextA) {
    if (v.lightIndex == kInvalidId || v.atInfinity || next.atInfinity) {
        originA = pdfLightOriginA(ctx, v);
        towardsNextA = pdfLightDirectionA(ctx, v, next);
        return;
    }
    // One pdfEmission call for both (its pdfPosA does not depend on the direction).
    Vec3f w = directionTo(v, next);
    float pdfDirW;
    ctx.scene.lights().pdfEmission(v.lightIndex, v.ng, w, originA, pdfDirW);
    towardsNextA = w == Vec3f(0.f) ? 0.f : convertDensity(pdfDirW, v, next);
}

namespace {

/// σa of the segment from `v` towards `other` as seen from `v`: surface vertices by their BSDF
/// inputs, a light vertex on an area emitter by the emitter's material; zero for the rest.
Rgb endSigma(const RenderContext& ctx, const PathVertex& v, const PathVertex& other) {
    if (v.type == VertexType::Surface) {
        // Most surfaces are no volume boundary: skip the direction (a square root) for them.
        if (v.bsdf.thinWalled || isBlack(v.bsdf.attenuationCoeff)) return Rgb(0.f);
        return volumeSigmaAt(v.bsdf, v.ng, directionTo(v, other));
    }
    if (v.type == VertexType::Light && !v.atInfinity) return emitterVolumeSigma(ctx.scene, v.lightIndex, v.ng, directionTo(v, other));
    return Rgb(0.f);
}

}  // namespace

Rgb segmentTransmittanceInVolumes(const RenderContext& ctx, const PathVertex& a, const PathVertex& b, bool& attenuates) {
    attenuates = false;
    Rgb sigmaA = endSigma(ctx, a, b), sigmaB = endSigma(ctx, b, a);
    attenuates = segmentAttenuates(sigmaA, sigmaB);
    if (!attenuates) return Rgb(1.f);
    float length = a.atInfinity || b.atInfinity ? kInfiniteSegment : glm::length(b.p - a.p);
    return segmentTransmittance(sigmaA, sigmaB, length);
}

Rgb evalVertex(const RenderContext& ctx, const PathVertex& v, const PathVertex& next, TransportMode mode) {
    Vec3f w = directionTo(v, next);
    if (w == Vec3f(0.f)) return Rgb(0.f);
    return evalVertexTowards(ctx, v, w, mode);
}

Rgb evalVertexTowards(const RenderContext& ctx, const PathVertex& v, const Vec3f& w, TransportMode mode) {
    switch (v.type) {
    case VertexType::Camera:
        return Rgb(ctx.camera.importance(v.p, w));
    case VertexType::Light:
        // Radiance (area lights), intensity towards w (point, spot lights).
        return ctx.scene.lights().emitted(v.lightIndex, v.ng, w, v.bary);
    case VertexType::Surface: {
        SurfaceBsdf bsdf(v.bsdf, v.ns, v.ng, SurfaceBsdf::Use::EvalOnly);
        return bsdf.eval(v.woWorld, w, mode);
    }
    }
    return Rgb(0.f);
}

Rgb emittedAt(const RenderContext& ctx, const PathVertex& v) {
    if (v.lightIndex == kInvalidId) return Rgb(0.f);
    if (v.type == VertexType::Light && v.atInfinity) return ctx.scene.lights().environmentLe(v.ng);
    if (v.type != VertexType::Surface) return Rgb(0.f);
    return ctx.scene.lights().emitted(v.lightIndex, v.ng, v.woWorld, v.bary);
}

namespace {

/// Extends a sub-path whose last vertex is `out.back()` along `ray` (Veach 1997, §10.2: each
/// vertex sampled from its predecessor with the local density, converted to area). `beta` is the
/// throughput carried by the ray.
void randomWalk(const RenderContext& ctx, Ray ray, Rgb beta, Sampler& sampler, TransportMode mode,
                int maxVertices, std::vector<PathVertex>& out) {
    const Scene& scene = ctx.scene;
    float rrScale = 1.f;  // product of BSDF weights (and η² for radiance): what Russian roulette looks at
    int scatteringVertices = 0;  // vertices so far that sampled a non-delta lobe (roulette's depth)
    int limit = maxVertices < 0 ? kMaxSubpathVertices : std::min(maxVertices, kMaxSubpathVertices);
    // The BSDF the last surface vertex sampled its direction with: the next vertex's two densities
    // at that vertex come from the same object (no second frame and copy per vertex).
    std::optional<SurfaceBsdf> lastBsdf;
    while (int(out.size()) < limit) {
        Hit hit;
        // The camera ray (a camera subpath's first segment) follows its neighbours: the coherent kernel.
        bool cameraRay = mode == TransportMode::Radiance && out.size() == 1;
        bool found = cameraRay ? ctx.accel.intersectCoherent(ray, hit) : ctx.accel.intersect(ray, hit);
        // Built in place at the end of the sub-path (no copy of a vertex per bounce); `out` keeps
        // its capacity between samples (the callers' thread-local vectors).
        const size_t n = out.size();
        PathVertex& v = out.emplace_back();
        if (found) {
            SurfaceInteraction si = scene.interaction(ray, hit);
            v.type = VertexType::Surface;
            v.p = si.p;
            v.ng = si.ng;
            v.ns = si.ns;
            v.woWorld = -glm::normalize(ray.d);
            v.bsdf = scene.bsdfParams(si, ctx.camera.pixelFootprint(si.p));
            v.lightIndex = si.lightIndex;
            v.bary = si.bary;
        } else {
            // A camera ray that escapes reaches the environment: the sub-path ends with a vertex at
            // infinity, the s = 0 strategy's emitter (pbrt-v3 §16.3.2). Light sub-paths just end.
            if (mode != TransportMode::Radiance || !scene.lights().hasEnvironment()) {
                out.pop_back();
                break;
            }
            v.type = VertexType::Light;
            v.atInfinity = true;
            v.ng = v.ns = glm::normalize(ray.d);
            v.p = ray.o + (2.f * scene.lights().sceneRadius() + glm::length(ray.o - scene.lights().sceneCenter())) * v.ng;
            v.lightIndex = scene.lights().environmentIndex();
        }
        // The segment back to the predecessor, once for every density towards it (PathVertex::toPrev).
        if (const PathVertex& pred = out[n - 1]; !pred.atInfinity && !v.atInfinity) {
            segmentBetween(v.p, pred.p, v.toPrevDist2, v.toPrevLen, v.toPrev);
            if (v.toPrevDist2 > 0.f) v.prevP = pred.p;
            else v.toPrevLen = 0.f;
        }
        // The segment just traced: Beer–Lambert inside a volume (the same rule as the connections).
        // Roulette keeps looking at the BSDF weights only (as in pt).
        bool attenuates;
        Rgb T = segmentTransmittance(ctx, out[n - 1], v, attenuates);
        if (attenuates) beta *= T;
        v.beta = beta;
        // Densities are evaluated from the vertex positions rather than taken from the sampling
        // routine: the connection code evaluates them the same way, so every strategy sees exactly
        // the same p→/p← for a vertex and the weights sum to one to rounding (grazing cosine-
        // hemisphere samples otherwise differ by a few percent). After a delta scattering the
        // density is the delta's unit weight converted to area (deltaDensityA).
        const PathVertex& prev = out[n - 1];
        // The successor now exists: the density of the predecessor's predecessor being sampled
        // from `prev` given `v` (Veach's p←), i.e. pdfRevA of out[n − 2].
        if (prev.delta) {
            v.pdfFwdA = deltaDensityA(prev, v);
            if (n >= 2) out[n - 2].pdfRevA = deltaDensityA(prev, out[n - 2]);
        } else if (n >= 2) {
            pdfBothWaysA(ctx, *lastBsdf, out[n - 2], prev, v, v.pdfFwdA, out[n - 2].pdfRevA);  // prev: a surface
        } else {
            v.pdfFwdA = pdfNextA(ctx, nullptr, prev, v);
        }
        if (!found || int(out.size()) >= limit) break;

        PathVertex& cur = out.back();
        const SurfaceBsdf& bsdf = lastBsdf.emplace(cur.bsdf, cur.ns, cur.ng);
        SurfaceBsdfSample bs;
        if (mode == TransportMode::Radiance) sampler.startBounce(int(out.size()) - 2);
        else sampler.startLightBounce(int(out.size()) - 2);
        if (!bsdf.sample(cur.woWorld, sampler, mode, bs)) break;
        cur.delta = bs.isDelta;
        beta *= bs.weight;
        rrScale *= maxComponent(bs.weight) * (mode == TransportMode::Radiance ? bs.eta * bs.eta : 1.f);
        if (isBlack(beta)) break;
        if (!bs.isDelta) ++scatteringVertices;
        // Russian roulette from the second non-delta vertex on (integrators/russian_roulette.h);
        // the throughput of the vertices before it is played there.
        if (scatteringVertices >= 2 && !survivesRoulette(rrScale, beta, sampler, /* trace = */ nullptr)) break;
        ray = spawnRay(cur.p, cur.ng, bs.wiWorld);
    }
}

}  // namespace

void traceCameraSubpath(const RenderContext& ctx, Vec2f raster, Sampler& sampler, int maxVertices, std::vector<PathVertex>& out) {
    out.clear();
    if (maxVertices == 0) return;
    Ray ray = ctx.camera.generateRay(raster, sampler.get2D());
    PathVertex& z0 = out.emplace_back();  // built in place, as randomWalk builds its vertices
    z0.type = VertexType::Camera;
    z0.p = ray.o;
    z0.ng = z0.ns = ctx.camera.forward();
    // Box-filtered pixel: We cos / (pdfPosA pdfDirW) = 1 for the pixel the ray was generated in.
    z0.beta = Rgb(1.f);
    z0.pdfFwdA = 1.f / ctx.camera.lensArea();  // generateRay's pdfPosA; never used by the weights (no strategy hits the lens)
    randomWalk(ctx, ray, Rgb(1.f), sampler, TransportMode::Radiance, maxVertices, out);
}

void traceLightSubpath(const RenderContext& ctx, Sampler& sampler, int maxVertices, std::vector<PathVertex>& out) {
    out.clear();
    const LightSet& lights = ctx.scene.lights();
    if (maxVertices == 0 || lights.empty()) return;
    sampler.startLightPath();
    float uPick = sampler.get1D();
    Vec2f uPos = sampler.get2D();
    Vec2f uDir = sampler.get2D();
    LightEmission le;
    if (!lights.sampleEmission(uPick, uPos, uDir, le) || isBlack(le.Le)) return;
    PathVertex& y0 = out.emplace_back();
    y0.type = VertexType::Light;
    y0.p = le.p;
    y0.ng = y0.ns = le.isInfinite ? -le.dir : le.n;
    y0.atInfinity = le.isInfinite;
    y0.lightIndex = le.index;
    y0.bary = le.bary;
    // y0 carries 1/pdfPosA; its "f" towards the next vertex is the emitted radiance (intensity). An
    // infinite light's origin density is that of its direction (pdfLightOriginA); its y0 is never
    // connected (not connectible), so its beta is unused.
    y0.beta = Rgb(1.f / le.pdfPosA);
    y0.pdfFwdA = le.isInfinite ? le.pdfDirW : le.pdfPosA;
    // Infinite lights: the ray leaves the disk along the direction, cos = 1, and β = L / (pdfPos ·
    // pdfDir) is the radiance through the disk's area per unit solid angle (pbrt-v3 §16.3.1).
    float cosLight = le.isDeltaPos || le.isInfinite ? 1.f : std::abs(glm::dot(le.n, le.dir));
    Rgb beta = le.Le * (cosLight / (le.pdfPosA * le.pdfDirW));
    Ray ray = le.isDeltaPos || le.isInfinite ? Ray{le.p, le.dir, 0.f, kInfinity} : spawnRay(le.p, le.n, le.dir);
    randomWalk(ctx, ray, beta, sampler, TransportMode::Importance, maxVertices, out);
}

}  // namespace tessera
