#include "integrators/sppm.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
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

SppmIntegrator::SppmIntegrator(PhotonSettings settings) : settings_(settings) {
    if (settings_.radius == 0.f) throw InputError("sppm: --radius 0 leaves no merging, and sppm finds light only by merging");
}

void SppmIntegrator::preparePass(const RenderContext& ctx, uint32_t firstSample, uint32_t count, uint64_t seed, SamplerKind kind,
                                 ThreadPool& pool) const {
    // Built anew on every call: the map depends on the seed, the film size and the depth limit as
    // well as the iteration, and one integrator may serve several renders (tessera view).
    if (count == 0) return;
    pass_.prepare(ctx, settings_, firstSample, seed, kind, pool,
                  [](const std::vector<PathVertex>& path, std::vector<Photon>& photons, std::vector<Vec3f>& positions) {
                      for (size_t j = 1; j < path.size(); ++j) {
                          const PathVertex& v = path[j];
                          // A vertex whose material has no non-delta lobe reflects nothing a merge can see.
                          if (v.type != VertexType::Surface || isDeltaMaterial(v.bsdf)) continue;
                          photons.push_back({v.woWorld, v.beta, uint32_t(j)});
                          positions.push_back(v.p);
                      }
                  });
}

Rgb SppmIntegrator::sample(const RenderContext& ctx, Vec2i, Vec2f raster, Sampler& sampler, SplatSink&) const {
    pass_.requireIteration(sampler, "sppm");
    const Scene& scene = ctx.scene;
    Ray ray = ctx.camera.generateRay(raster, sampler.get2D());
    Rgb L(0.f), beta(1.f);
    float rrScale = 1.f;
    Rgb sigmaLeave(0.f);
    Vec3f prevP = ray.o;
    const float radius = pass_.radius;
    const float mergeNorm = 1.f / (float(pass_.paths) * kPi * radius * radius);
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
            pass_.grid.forEachWithin(si.p, radius, [&](uint32_t i) {
                const Photon& ph = pass_.photons[i];
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
        if (!bsdf.sample(wo, sampler, TransportMode::Radiance, bs) || !bs.isDelta) break;
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
