#include "integrators/sppm.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/thread_pool.h"
#include "integrators/path_vertex.h"
#include "integrators/russian_roulette.h"
#include "integrators/volume.h"
#include "materials/surface_bsdf.h"

namespace tessera {

// Why this converges (Knaus & Zwicker 2011): iteration i estimates the radiance leaving a camera
// vertex x towards the camera by the photons within r_i of x,
//     L_i(x, wo) = Σ_p f(wo, wi_p) Φ_p / (N π r_i²),
// where Φ_p is the throughput of the light sub-path that left photon p (an unbiased estimate of
// the power it carries, as in light tracing) and N the sub-paths of the iteration. Its expectation
// is the radiance convolved with a disk kernel of radius r_i: biased by O(r_i²) where the
// illumination curves, with variance O(1/(N r_i²)). KZ11 show that with r_(i+1)² = r_i² (i + α)/(i + 1)
// the average of the L_i has vanishing bias and variance (α < 1 keeps the variance of the average
// falling while the radius shrinks), which the film's average over sample indices is. Emission is
// added only where the camera reached it through delta scattering alone: every other path to a
// light is counted by a photon (its direct illumination, j = 1) and must not be counted twice.

float SppmIntegrator::iterationRadius(float radius, float alpha, uint32_t iteration) {
    double r2 = double(radius) * double(radius);
    for (uint32_t k = 1; k <= iteration; ++k) r2 *= (double(k) + double(alpha)) / double(k + 1);
    return float(std::sqrt(r2));
}

void SppmIntegrator::preparePass(const RenderContext& ctx, uint32_t firstSample, uint32_t count, uint64_t seed, SamplerKind kind,
                                 ThreadPool& pool) const {
    // Built anew on every call: the map depends on the seed, the film size and the depth limit as
    // well as the iteration, and one integrator may serve several renders (tessera view).
    if (count == 0) return;
    iteration_ = firstSample;
    paths_ = settings_.photons > 0 ? settings_.photons : uint64_t(ctx.camera.width()) * uint64_t(ctx.camera.height());
    // Default r_1: SmallVCM's 0.003 × the scene's radius at its 512² light sub-paths, grown as
    // 1/√paths below that so that a query finds about as many photons at any resolution.
    const float r1 = settings_.radius > 0.f ? settings_.radius
                                            : 0.003f * ctx.scene.lights().sceneRadius() * float(std::sqrt(std::max(1.0, 262144.0 / double(paths_))));
    radius_ = iterationRadius(r1, settings_.alpha, firstSample);
    // Light sub-paths in chunks, each chunk's photons in path order, chunks concatenated in order:
    // the photon list, and so every query's visiting order, is the same for any thread count.
    // Path k draws from the sampler of "pixel" (k, −1), a row no camera sample uses.
    constexpr uint64_t kChunk = 1024;
    const size_t chunks = size_t((paths_ + kChunk - 1) / kChunk);
    std::vector<std::vector<Photon>> chunkPhotons(chunks);
    std::vector<std::vector<Vec3f>> chunkPositions(chunks);
    const int maxVertices = ctx.maxDepth < 0 ? -1 : ctx.maxDepth + 1;
    pool.parallelFor(chunks, [&](size_t c) {
        thread_local std::vector<PathVertex> path;
        for (uint64_t k = c * kChunk; k < std::min(paths_, (c + 1) * kChunk); ++k) {
            Sampler sampler(Vec2i(int(k), -1), firstSample, seed, kind);
            traceLightSubpath(ctx, sampler, maxVertices, path);
            for (size_t j = 1; j < path.size(); ++j) {
                const PathVertex& v = path[j];
                // A vertex whose material has no non-delta lobe reflects nothing a merge can see.
                if (v.type != VertexType::Surface || isDeltaMaterial(v.bsdf)) continue;
                chunkPhotons[c].push_back({v.woWorld, v.beta, uint32_t(j)});
                chunkPositions[c].push_back(v.p);
            }
        }
    });
    photons_.clear();
    std::vector<Vec3f> positions;
    for (size_t c = 0; c < chunks; ++c) {
        photons_.insert(photons_.end(), chunkPhotons[c].begin(), chunkPhotons[c].end());
        positions.insert(positions.end(), chunkPositions[c].begin(), chunkPositions[c].end());
    }
    grid_.build(positions, radius_, &pool);
}

Rgb SppmIntegrator::sample(const RenderContext& ctx, Vec2i, Vec2f raster, Sampler& sampler, SplatSink&) const {
    // Without its iteration's photons (a sample outside the pass preparePass made) the estimate
    // would silently use another iteration's: refuse loudly instead.
    if (sampler.sampleIndex() != iteration_)
        throw std::logic_error("sppm: sample index " + std::to_string(sampler.sampleIndex()) + " rendered without its photon map");
    const Scene& scene = ctx.scene;
    Ray ray = ctx.camera.generateRay(raster, sampler.get2D());
    Rgb L(0.f), beta(1.f);
    float rrScale = 1.f;
    Rgb sigmaLeave(0.f);
    Vec3f prevP = ray.o;
    const float mergeNorm = 1.f / (float(paths_) * kPi * radius_ * radius_);
    for (int depth = 0;; ++depth) {
        Hit hit;
        if (!(depth == 0 ? ctx.accel.intersectCoherent(ray, hit) : ctx.accel.intersect(ray, hit))) {
            // The camera reached the environment through delta scattering alone (every other path
            // to it is a photon's).
            if (scene.lights().hasEnvironment()) {
                attenuateEscape(beta, sigmaLeave);
                L += beta * scene.lights().environmentLe(glm::normalize(ray.d));
            }
            break;
        }
        SurfaceInteraction si = scene.interaction(ray, hit);
        const Vec3f wo = -glm::normalize(ray.d);
        const BsdfParams params = scene.bsdfParams(si, ctx.camera.pixelFootprint(si.p));
        attenuateArrival(beta, sigmaLeave, params, si.ng, wo, si.p, prevP);
        if (si.lightIndex != kInvalidId) L += beta * scene.lights().emitted(si.lightIndex, si.ng, wo, si.bary);
        const SurfaceBsdf bsdf(params, si.ns, si.ng);
        const int t = depth + 1;  // camera vertex index: segments from the camera
        if (!bsdf.isDelta()) {
            // Merge: the photons within r_i, with paths of at most maxDepth bounces (j + t − 1).
            Rgb sum(0.f);
            grid_.forEachWithin(si.p, radius_, [&](uint32_t i) {
                const Photon& ph = photons_[i];
                if (ctx.maxDepth >= 0 && int(ph.depth) + t - 1 > ctx.maxDepth) return;
                sum += bsdf.eval(wo, ph.wi, TransportMode::Radiance) * ph.power;
            });
            L += beta * sum * mergeNorm;
            // A Lambertian point has no delta lobe to go on through: its sample would only end the path.
            if (params.type == MaterialType::Diffuse) break;
        }
        if (ctx.maxDepth >= 0 && depth >= ctx.maxDepth) break;
        // Continue only through delta lobes: a non-delta continuation is what the merge above
        // estimated (its sampled direction would count the same light again).
        sampler.startBounce(depth);
        SurfaceBsdfSample bs;
        float uLobe = sampler.get1D();
        Vec2f uDir = sampler.get2D();
        if (!bsdf.sample(wo, uLobe, uDir, TransportMode::Radiance, bs) || !bs.isDelta) break;
        beta *= bs.weight;
        rrScale *= maxComponent(bs.weight) * bs.eta * bs.eta;
        if (isBlack(beta)) break;
        if (depth >= kRouletteMinDepth && !survivesRoulette(rrScale, beta, sampler, nullptr)) break;
        ray = spawnRay(si.p, si.ng, bs.wiWorld);
        sigmaLeave = volumeSigmaAt(params, si.ng, bs.wiWorld);
        prevP = si.p;
    }
    return L;
}

}  // namespace tessera
