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
#include <vector>

#include "accel/photon_map.h"
#include "integrators/integrator.h"

namespace tessera {

struct SppmSettings {
    /// r_1 in scene units; ≤ 0: 0.003 × the radius of the scene's bounding sphere (SmallVCM's
    /// default radius factor) × √(512² / photons) where there are fewer photons than that.
    float radius = 0.f;
    float alpha = 0.75f;     ///< KZ11's α ∈ (0, 1): how fast the radius shrinks
    uint64_t photons = 0;    ///< light sub-paths per iteration; 0: one per pixel (as SmallVCM)
};

class SppmIntegrator final : public Integrator {
public:
    explicit SppmIntegrator(SppmSettings settings = {}) : settings_(settings) {}
    std::string_view name() const override { return "sppm"; }
    Rgb sample(const RenderContext& ctx, Vec2i pixel, Vec2f raster, Sampler& sampler, SplatSink& splats) const override;
    /// Traces the iteration's light sub-paths and builds its photon map (one iteration per pass).
    void preparePass(const RenderContext& ctx, uint32_t firstSample, uint32_t count, uint64_t seed, SamplerKind kind,
                     ThreadPool& pool) const override;
    uint32_t maxPassSamples() const override { return 1; }

    /// r_i of iteration i (sample index i, from 0): r_0 = `radius`, then KZ11's sequence.
    static float iterationRadius(float radius, float alpha, uint32_t iteration);

private:
    /// What a light sub-path leaves at a surface vertex with a non-delta lobe.
    struct Photon {
        Vec3f wi;        ///< unit direction towards the previous light vertex
        Rgb power;       ///< the sub-path's throughput arriving at the vertex (Veach's α_L)
        uint32_t depth;  ///< light vertex index j ≥ 1 (segments from the light)
    };

    SppmSettings settings_;
    // The current iteration's photon map: written by preparePass between passes only, read by
    // sample() during the pass (the scheduler's pool orders the two).
    mutable uint32_t iteration_ = 0xffffffffu;
    mutable float radius_ = 0.f;
    mutable uint64_t paths_ = 0;
    mutable std::vector<Photon> photons_;
    mutable PhotonHashGrid grid_;
};

}  // namespace tessera
