#pragma once
/// \file renderer.h
/// The tiled, multithreaded scheduler. The image is cut into square tiles rendered by a TBB task
/// arena in progressive passes (1, 1, 2, 4, … samples per pixel, at most 16 per pass). Every sample
/// is seeded by (pixel, sample index, seed), each tile accumulates its pixels' samples in index
/// order and splats are merged in tile order, so the image is bit-identical for any thread count.
#include <atomic>
#include <cstdint>

#include "integrators/integrator.h"
#include "render/film.h"
#include "render/progress.h"

namespace tessera {

struct RenderOptions {
    int spp = 16;                   ///< samples per pixel (ignored when timeLimitSeconds > 0)
    double timeLimitSeconds = 0.0;  ///< > 0: render passes until this budget is spent
    int threads = 0;                ///< 0 = all cores
    uint64_t seed = 0;
    int tileSize = 32;
    const std::atomic<bool>* cancel = nullptr;  ///< checked before every tile
    ProgressReporter* progress = nullptr;
};

struct RenderStats {
    uint32_t sppCompleted = 0;    ///< samples per pixel of every pixel (complete passes)
    uint64_t samples = 0;         ///< camera samples taken, including a partial last pass
    uint64_t nonFiniteDropped = 0;  ///< samples (or splats) that were NaN/Inf and never reached the film
    double seconds = 0.0;
    bool interrupted = false;
    int threads = 0;
};

RenderStats renderImage(const RenderContext& ctx, const Integrator& integrator, Film& film, const RenderOptions& options);

}  // namespace tessera
