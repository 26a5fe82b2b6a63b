#pragma once
/// \file renderer.h
/// The tiled, multithreaded scheduler. The image is cut into square tiles rendered by our own thread
/// pool (core/thread_pool.h) in progressive passes (1, 1, 2, 4, … samples per pixel, at most 16 per pass). Every sample
/// is seeded by (pixel, sample index, seed), each tile accumulates its pixels' samples in index
/// order and splats are merged in tile order, so the image is bit-identical for any thread count.
#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "integrators/integrator.h"
#include "render/film.h"
#include "render/progress.h"

namespace tessera {

/// The camera sample that produced the first non-finite value of a render: the smallest
/// (sample, y, x), so the answer does not depend on which thread got there first.
struct SampleId {
    int x = 0, y = 0;
    uint32_t sample = 0;
    bool operator<(const SampleId& o) const {
        return sample != o.sample ? sample < o.sample : y != o.y ? y < o.y : x < o.x;
    }
};

/// Where a render stands: what the scheduler needs besides the film to continue it bit for bit
/// (render/checkpoint.h stores both). At a pass boundary `tileDone` is empty. A render stopped in
/// the middle of a pass lists that pass's finished tiles (already in the film's per-pixel sums)
/// and keeps their splats unmerged: splats must be merged in tile order to give the same bits.
struct RenderState {
    uint32_t sppDone = 0;    ///< samples per pixel of every complete pass
    uint32_t passSpp = 1;    ///< samples per pixel of the next pass (of the partial one when tileDone is set)
    uint64_t samples = 0;    ///< camera samples of the complete passes
    uint64_t nonFinite = 0;  ///< non-finite samples and splats dropped so far
    double seconds = 0.0;    ///< render time of all sessions so far
    std::optional<SampleId> firstNonFinite;
    std::vector<uint8_t> tileDone;                              ///< partial pass: 1 per finished tile
    std::vector<std::vector<SplatSink::Entry>> pendingSplats;  ///< partial pass: each tile's unmerged splats
};

struct RenderOptions {
    int spp = 16;                   ///< samples per pixel (ignored when timeLimitSeconds > 0)
    /// Render sample indices [firstSample, spp) of every pixel (`render --samples A:B`): exactly
    /// the samples a render from 0 draws for those indices. Not with timeLimitSeconds or resume.
    uint32_t firstSample = 0;
    double timeLimitSeconds = 0.0;  ///< > 0: render passes until this budget is spent
    int threads = 0;                ///< 0 = all cores the process may use (hardwareThreads())
    uint64_t seed = 0;
    int tileSize = 32;
    const std::atomic<bool>* cancel = nullptr;  ///< checked before every tile
    ProgressReporter* progress = nullptr;
    /// Continue from this state; the film must already hold the sums that go with it.
    const RenderState* resume = nullptr;
    /// Called with the film and the state to continue from after every complete pass
    /// (`interrupted` true when the render stops there), and once when the render stops in the
    /// middle of a pass, before that pass's splats are merged for the output image.
    std::function<void(const Film& film, const RenderState& state, bool interrupted)> onPassEnd = {};
    /// Test hook: behave as if cancelled once this many tiles have been rendered (0: never).
    uint64_t stopAfterTiles = 0;
};

struct RenderStats {
    uint32_t sppCompleted = 0;    ///< samples per pixel of every pixel (complete passes; past firstSample)
    uint64_t samples = 0;         ///< camera samples taken, including a partial last pass
    uint64_t nonFiniteDropped = 0;  ///< samples (or splats) that were NaN/Inf and never reached the film
    double seconds = 0.0;         ///< all sessions, when resumed
    std::optional<SampleId> firstNonFinite;
    bool interrupted = false;
    int threads = 0;
};

RenderStats renderImage(const RenderContext& ctx, const Integrator& integrator, Film& film, const RenderOptions& options);

}  // namespace tessera
