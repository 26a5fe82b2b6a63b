#pragma once
/// \file vcm.h
/// `vcm`: vertex connection and merging (Georgiev, Křivánek, Davidovič & Slusallek, "Light
/// Transport Simulation with Vertex Connection and Merging", SIGGRAPH Asia 2012; the estimator
/// bookkeeping after I. Georgiev, "Implementing Vertex Connection and Merging", tech. report 2012).
/// Every sample index is one iteration: N light sub-paths deposit photons (photon_pass.h, as
/// `sppm`), and each camera sample runs every BDPT strategy (s, t) of `bdpt` on its own camera and
/// light sub-paths *and* merges each of its camera vertices with the photons within r_i. One MIS
/// weight covers both kinds (bdpt_mis.h's (‡)): connections win where paths are easy to connect,
/// merging where they are not (caustics seen through mirrors, point-light caustics). With radius
/// 0 there is no merging and the image is `bdpt`'s, bit for bit.
#include <span>

#include "integrators/bdpt.h"
#include "integrators/photon_pass.h"

namespace tessera {

/// A light vertex as a merge needs it: position in the grid, what it carries, and the light side's
/// MIS sum with the one density only the merge knows divided out (the tech report's dVCM/dVM
/// trick, eqs. 34–36: the camera BSDF's density towards the photon's predecessor).
struct VcmPhoton {
    Vec3f wi;           ///< unit direction towards the previous light vertex y(j−1)
    Rgb power;          ///< the light sub-path's throughput arriving at the vertex (α_L)
    uint32_t depth;     ///< light vertex index j ≥ 1
    float pdfFwdA;      ///< p→(y_j): area density of y_j sampled from y(j−1)
    float toPrevConv;   ///< solid angle at y_j → area at y(j−1): |cos θ(j−1)| / d² (1 at infinity)
    double connTerm;    ///< c_j g_j of (‡): strategy joining y(j−1) and y_j (y_j scattering non-delta)
    double restOverFwd; ///< the bracket of (‡) at y(j−1) over p→(y(j−1))^β: M'_(j−1) = p←(y(j−1))^β · this
};

/// The photons of light sub-path `path` (after bdptMisPrefixes(ctx, path, {}, heuristic, eta)):
/// one per vertex j ≥ 1 whose material has a non-delta lobe, appended with their positions.
void vcmPhotonsOfPath(const RenderContext& ctx, std::span<const PathVertex> path, MisHeuristic heuristic, double eta,
                      std::vector<VcmPhoton>& photons, std::vector<Vec3f>& positions);

/// The MIS weight of merging camera vertex z(t−1) (t ≥ 2; `bsdfAtX` its BSDF) with `photon`,
/// treating the photon as lying at z(t−1) (the merge's path is y0 … y(j−1) z(t−1) … z0).
/// bdptMisPrefixes must have run on `camera` with the same `eta` > 0.
float vcmMergeWeight(const RenderContext& ctx, const VcmPhoton& photon, std::span<const PathVertex> camera, int t,
                     const SurfaceBsdf& bsdfAtX, double eta, MisHeuristic heuristic);

class VcmIntegrator final : public Integrator {
public:
    explicit VcmIntegrator(PhotonSettings photons = {}, MisHeuristic heuristic = MisHeuristic::Power)
        : photons_(photons), heuristic_(heuristic) {}
    std::string_view name() const override { return "vcm"; }
    Rgb sample(const RenderContext& ctx, Vec2i pixel, Vec2f raster, Sampler& sampler, SplatSink& splats) const override;
    void preparePass(const RenderContext& ctx, uint32_t firstSample, uint32_t count, uint64_t seed, SamplerKind kind,
                     ThreadPool& pool) const override;
    /// One iteration per pass; without merging (radius 0) passes of any size, as bdpt's.
    uint32_t maxPassSamples() const override { return photons_.radius == 0.f ? 0 : 1; }

private:
    PhotonSettings photons_;
    MisHeuristic heuristic_;
    mutable IterationPhotons<VcmPhoton> pass_;  ///< the current iteration's photons
};

}  // namespace tessera
