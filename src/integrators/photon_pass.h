#pragma once
/// \file photon_pass.h
/// What the photon-mapping integrators (`sppm`, `vcm`) share: their settings, the radius sequence,
/// and one iteration's light sub-paths traced in parallel into a photon list with its hash grid.
/// One iteration is one sample index (Knaus & Zwicker 2011's probabilistic form): its photons are
/// a function of (iteration, seed, sampler kind, scene, film size) alone, so resumed renders and
/// sample-range parts prepare exactly the photons of a full render.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "accel/photon_map.h"
#include "core/thread_pool.h"
#include "integrators/path_vertex.h"

namespace tessera {

struct PhotonSettings {
    /// r_1 in scene units; < 0: defaultMergeRadius. 0: no merging (vcm: its connections alone,
    /// i.e. bdpt; sppm refuses it).
    float radius = -1.f;
    float alpha = 0.75f;   ///< KZ11's α ∈ (0, 1): how fast the radius shrinks
    uint64_t photons = 0;  ///< light sub-paths per iteration; 0: one per pixel (as SmallVCM)
};

/// r_i of iteration i (sample index i, from 0): r_0 = `radius`, then Knaus & Zwicker 2011's global
/// sequence r_(i+1)² = r_i² (i + α)/(i + 1) (their eq. 20, i counted from 1).
float photonIterationRadius(float radius, float alpha, uint32_t iteration);

/// The default r_1 for `paths` light sub-paths per iteration: SmallVCM's 0.003 × the radius of the
/// scene's bounding sphere at its 512² paths, grown as √(512² / paths) below that so that a query
/// finds about as many photons at any resolution; but never more than one pixel's footprint at the
/// median depth the camera sees (16 × 16 rays through the film), grown as √(pixels / paths). The
/// cap matters where the bounding sphere says nothing about what is seen: smallpt-style walls that
/// are spheres of radius 10⁵ made SmallVCM's rule merge over the whole room (sphere-cornell: r ≈ 700
/// in a box of 100, images 28× too bright at 4 iterations). A function of the scene and camera alone.
float defaultMergeRadius(const RenderContext& ctx, uint64_t paths);

/// One iteration's photons and their grid. Written by prepare() between passes only, read by the
/// samples of the pass (the scheduler's pool orders the two).
template <class Photon>
struct IterationPhotons {
    uint32_t iteration = 0xffffffffu;
    float radius = 0.f;   ///< r_i
    uint64_t paths = 0;   ///< light sub-paths traced (N)
    std::vector<Photon> photons;
    PhotonHashGrid grid;

    /// Traces `settings.photons` light sub-paths (one per pixel by default) for iteration
    /// `firstSample` and keeps what `deposit(path, photons, positions)` appends for each. Path k
    /// draws from the sampler of "pixel" (k, −1), a row no camera sample uses; chunks of paths are
    /// traced in parallel and concatenated in path order, so the list, and every query's visiting
    /// order, is the same for any thread count.
    template <class Deposit>
    void prepare(const RenderContext& ctx, const PhotonSettings& settings, uint32_t firstSample, uint64_t seed, SamplerKind kind,
                 ThreadPool& pool, Deposit&& deposit) {
        iteration = firstSample;
        paths = settings.photons > 0 ? settings.photons : uint64_t(ctx.camera.width()) * uint64_t(ctx.camera.height());
        const float r1 = settings.radius >= 0.f ? settings.radius : defaultMergeRadius(ctx, paths);
        radius = photonIterationRadius(r1, settings.alpha, firstSample);
        photons.clear();
        if (!(radius > 0.f)) return;
        constexpr uint64_t kChunk = 1024;
        const size_t chunks = size_t((paths + kChunk - 1) / kChunk);
        std::vector<std::vector<Photon>> chunkPhotons(chunks);
        std::vector<std::vector<Vec3f>> chunkPositions(chunks);
        const int maxVertices = ctx.maxDepth < 0 ? -1 : ctx.maxDepth + 1;
        pool.parallelFor(chunks, [&](size_t c) {
            thread_local std::vector<PathVertex> path;
            for (uint64_t k = c * kChunk; k < std::min(paths, (c + 1) * kChunk); ++k) {
                Sampler sampler(Vec2i(int(k), -1), firstSample, seed, kind);
                traceLightSubpath(ctx, sampler, maxVertices, path);
                deposit(path, chunkPhotons[c], chunkPositions[c]);
            }
        });
        std::vector<Vec3f> positions;
        for (size_t c = 0; c < chunks; ++c) {
            photons.insert(photons.end(), chunkPhotons[c].begin(), chunkPhotons[c].end());
            positions.insert(positions.end(), chunkPositions[c].begin(), chunkPositions[c].end());
        }
        grid.build(positions, radius, &pool);
    }

    /// Refuses a sample outside the iteration prepare() made: it would silently merge with
    /// another iteration's photons.
    void requireIteration(const Sampler& sampler, const char* integrator) const {
        if (sampler.sampleIndex() != iteration)
            throw std::logic_error(std::string(integrator) + ": sample index " + std::to_string(sampler.sampleIndex()) +
                                   " rendered without its photon map");
    }
};

}  // namespace tessera
