#pragma once
/// \file sppm.h
/// `sppm`: stochastic progressive photon mapping (Hachisuka & Jensen, "Stochastic Progressive
/// Photon Mapping", SIGGRAPH Asia 2009) in the probabilistic formulation of Knaus & Zwicker
/// ("Progressive Photon Mapping: A Probabilistic Approach", ACM TOG 30(3), 2011): every sample
/// index i is one iteration, with its own photons (`photons` light sub-paths) and its own radius
/// r_i, shrinking by KZ11's global sequence r_(i+1)² = r_i² (i + α)/(i + 1) (i from 1). Each
/// iteration's image is an independent estimate whose bias and variance both vanish as i grows;
/// the film's average over iterations converges (consistent, not unbiased). Camera paths are traced
/// anew each iteration (the "stochastic" of SPPM: lens, pixel area and glossy/specular chains are
/// integrated), and merge at every vertex with a non-delta lobe they reach through delta
/// scattering. No per-pixel statistics: each sample stays a pure function of (pixel, index,
/// seed), so sample-range renders merge bit-exactly and checkpoints resume like the other
/// integrators.
#include "integrators/integrator.h"
#include "integrators/photon_pass.h"

namespace tessera {

class SppmIntegrator final : public Integrator {
public:
    /// Throws InputError for a radius of 0 (no merging: sppm would see nothing but emitters).
    explicit SppmIntegrator(PhotonSettings settings = {});
    std::string_view name() const override { return "sppm"; }
    Rgb sample(const RenderContext& ctx, Vec2i pixel, Vec2f raster, Sampler& sampler, SplatSink& splats) const override;
    /// Traces the iteration's light sub-paths and builds its photon map (one iteration per pass).
    void preparePass(const RenderContext& ctx, uint32_t firstSample, uint32_t count, uint64_t seed, SamplerKind kind,
                     ThreadPool& pool) const override;
    uint32_t maxPassSamples() const override { return 1; }

private:
    /// What a light sub-path leaves at a surface vertex with a non-delta lobe.
    struct Photon {
        Vec3f wi;        ///< unit direction towards the previous light vertex
        Rgb power;       ///< the sub-path's throughput arriving at the vertex (Veach's α_L)
        uint32_t depth;  ///< light vertex index j ≥ 1 (segments from the light)
    };

    PhotonSettings settings_;
    mutable IterationPhotons<Photon> pass_;  ///< the current iteration's photons (photon_pass.h)
};

}  // namespace tessera
