#include "render/renderer.h"

#include <algorithm>
#include <chrono>
#include <mutex>
#include <stdexcept>
#include <string>

#include "core/fp_env.h"
#include "core/thread_pool.h"

namespace tessera {
namespace {

struct Tile {
    int x0, y0, x1, y1;
    uint64_t pixels() const { return uint64_t(x1 - x0) * uint64_t(y1 - y0); }
};

constexpr uint32_t kMaxPassSpp = 16;

std::vector<Tile> makeTiles(int width, int height, int tileSize) {
    const int ts = std::max(1, tileSize);
    std::vector<Tile> tiles;
    for (int y = 0; y < height; y += ts)
        for (int x = 0; x < width; x += ts) tiles.push_back({x, y, std::min(x + ts, width), std::min(y + ts, height)});
    return tiles;
}

/// One call of renderImage: the tiles, their splat sinks and the counters shared by the workers.
class TileScheduler {
public:
    TileScheduler(const RenderContext& ctx, const Integrator& integrator, Film& film, const RenderOptions& opt)
        : ctx_(ctx), integrator_(integrator), film_(film), opt_(opt), tiles_(makeTiles(film.width(), film.height(), opt.tileSize)),
          splats_(tiles_.size()), tileDone_(tiles_.size(), 0), st_(opt.resume ? *opt.resume : RenderState{}),
          nonFinite_(st_.nonFinite), firstNonFinite_(st_.firstNonFinite) {
        if (opt.firstSample > 0 && (opt.resume || opt.timeLimitSeconds > 0.0))
            throw std::invalid_argument("renderImage: a sample range cannot be time-bounded or resumed");
        if (!opt.resume) s0_ = opt.firstSample;
        if (!st_.tileDone.empty() && (st_.tileDone.size() != tiles_.size() || st_.pendingSplats.size() != tiles_.size()))
            throw std::invalid_argument("renderImage: the resumed state has " + std::to_string(st_.tileDone.size()) +
                                        " tiles, the film " + std::to_string(tiles_.size()));
    }

    RenderStats run();

private:
    double elapsed() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }
    bool cancelled() const {
        return (opt_.cancel && opt_.cancel->load(std::memory_order_relaxed)) ||
               (opt_.stopAfterTiles > 0 && tilesRendered_.load(std::memory_order_relaxed) >= opt_.stopAfterTiles);
    }
    /// Marks the tiles the next pass must render: the resumed partial pass's unfinished ones, or all.
    void startPass();
    /// Samples [s0, s0 + n) of every pixel of tile t (one worker; tiles own disjoint pixels).
    void renderTile(size_t t, uint32_t s0, uint32_t n);
    /// Merges the finished tiles' splats into the film in tile order and counts their samples.
    void mergeSplats(uint32_t n, RenderStats& stats);
    /// Where the render stands after complete passes (and, with `withPartialPass`, inside one).
    RenderState stateNow(bool withPartialPass, uint64_t samples) const;

    const RenderContext& ctx_;
    const Integrator& integrator_;
    Film& film_;
    const RenderOptions& opt_;
    const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
    std::vector<Tile> tiles_;
    std::vector<SplatSink> splats_;
    std::vector<uint8_t> tileDone_;
    RenderState st_;  ///< the state resumed from (empty for a fresh render)
    bool resumePartial_ = !st_.tileDone.empty();
    uint32_t s0_ = st_.sppDone, passSpp_ = std::max(1u, st_.passSpp);
    std::atomic<uint64_t> nonFinite_;
    std::atomic<uint64_t> tilesRendered_{0};
    std::mutex firstMutex_;
    std::optional<SampleId> firstNonFinite_;
};

void TileScheduler::startPass() {
    if (resumePartial_) {
        // The pass the checkpoint stopped in: its finished tiles are in the film, their splats wait.
        tileDone_ = st_.tileDone;
        for (size_t t = 0; t < tiles_.size(); ++t) splats_[t].entries() = std::move(st_.pendingSplats[t]);
        resumePartial_ = false;
    } else {
        std::fill(tileDone_.begin(), tileDone_.end(), 0);
    }
}

void TileScheduler::renderTile(size_t t, uint32_t s0, uint32_t n) {
    // FTZ/DAZ while the tile renders, restored after it (MXCSR is per thread, and the caller's
    // thread renders tiles too, then goes on to read and write images).
    ScopedFlushToZero ftz;
    const Tile& tile = tiles_[t];
    SplatSink& sink = splats_[t];
    uint64_t bad = 0;
    std::optional<SampleId> tileFirst;
    for (int y = tile.y0; y < tile.y1; ++y)
        for (int x = tile.x0; x < tile.x1; ++x)
            for (uint32_t s = s0; s < s0 + n; ++s) {
                Sampler sampler(Vec2i(x, y), s, opt_.seed, opt_.sampler);
                Vec2f raster = Vec2f(float(x), float(y)) + sampler.get2D();
                size_t splatsBefore = sink.entries().size();
                Rgb L = integrator_.sample(ctx_, Vec2i(x, y), raster, sampler, sink);
                bool finite = isFinite(L);
                if (finite) film_.addSample(x, y, L);
                else ++bad;
                // Non-finite splats are dropped at the merge; note their sample here.
                for (size_t k = splatsBefore; finite && k < sink.entries().size(); ++k) finite = isFinite(sink.entries()[k].value);
                SampleId id{x, y, s};
                if (!finite && (!tileFirst || id < *tileFirst)) tileFirst = id;
            }
    if (bad) nonFinite_.fetch_add(bad, std::memory_order_relaxed);
    if (tileFirst) {
        std::lock_guard<std::mutex> lock(firstMutex_);
        if (!firstNonFinite_ || *tileFirst < *firstNonFinite_) firstNonFinite_ = tileFirst;
    }
    tileDone_[t] = 1;
    tilesRendered_.fetch_add(1, std::memory_order_relaxed);
    if (opt_.progress) opt_.progress->advance(tile.pixels() * n);
}

void TileScheduler::mergeSplats(uint32_t n, RenderStats& stats) {
    for (size_t t = 0; t < tiles_.size(); ++t) {
        if (!tileDone_[t]) continue;
        stats.samples += tiles_[t].pixels() * n;
        for (const SplatSink::Entry& e : splats_[t].entries()) {
            if (isFinite(e.value)) film_.addSplat(e.pixelIndex, e.value);
            else nonFinite_.fetch_add(1, std::memory_order_relaxed);
        }
        splats_[t].clear();
    }
}

RenderState TileScheduler::stateNow(bool withPartialPass, uint64_t samples) const {
    RenderState cp;
    cp.sppDone = s0_;
    cp.passSpp = passSpp_;
    cp.samples = samples;
    cp.nonFinite = nonFinite_.load();
    cp.seconds = st_.seconds + elapsed();
    cp.firstNonFinite = firstNonFinite_;
    if (withPartialPass) {
        cp.tileDone = tileDone_;
        cp.pendingSplats.resize(tiles_.size());
        for (size_t t = 0; t < tiles_.size(); ++t)
            if (tileDone_[t]) cp.pendingSplats[t] = splats_[t].entries();
    }
    return cp;
}

RenderStats TileScheduler::run() {
    RenderStats stats;
    // Our own pool, not TBB: its mutex/condition-variable hand-offs are visible to ThreadSanitizer,
    // so tools/sanitize.sh tests the scheduler that every build runs (writeup, "How correctness is tested").
    ThreadPool pool(opt_.threads);
    stats.threads = pool.threads();

    const bool timed = opt_.timeLimitSeconds > 0.0;
    const uint32_t target = timed ? 0xffffffffu : uint32_t(std::max(0, opt_.spp));
    const uint32_t s0Session = s0_;
    stats.samples = st_.samples;
    while (s0_ < target) {
        if (timed && s0_ > s0Session && !resumePartial_) {
            double used = elapsed(), perSpp = used / double(s0_ - s0Session), left = opt_.timeLimitSeconds - used;
            if (left <= 0.0) break;
            // Stop at a pass boundary: never start a pass predicted to overrun by more than one spp.
            passSpp_ = uint32_t(std::clamp(left / std::max(perSpp, 1e-9), 1.0, double(passSpp_)));
        }
        uint32_t n = std::min(passSpp_, target - s0_);
        if (uint32_t most = integrator_.maxPassSamples(); most > 0) n = std::min(n, most);
        startPass();
        integrator_.preparePass(ctx_, s0_, n, opt_.seed, opt_.sampler, pool);
        // One item per tile, claimed in tile order; parallelFor returns when the pass is done (the
        // barrier before the splat merge and the checkpoint). The interrupt flag is read before
        // every tile, so a stop request skips the tiles not yet started.
        pool.parallelFor(tiles_.size(), [&](size_t t) {
            if (!tileDone_[t] && !cancelled()) renderTile(t, s0_, n);
        });
        bool complete = std::all_of(tileDone_.begin(), tileDone_.end(), [](uint8_t d) { return d != 0; });
        // Stopped mid-pass: the checkpoint keeps this pass's splats unmerged (tile order, see above).
        if (!complete && opt_.onPassEnd) opt_.onPassEnd(film_, stateNow(/* withPartialPass = */ true, stats.samples), true);
        // Merge splats in tile order: the sums then do not depend on which thread ran which tile.
        mergeSplats(n, stats);
        if (!complete) {
            stats.interrupted = true;
            break;
        }
        s0_ += n;
        passSpp_ = std::min(kMaxPassSpp, passSpp_ * (s0_ >= 2 ? 2u : 1u));
        bool stop = cancelled();
        if (opt_.onPassEnd) opt_.onPassEnd(film_, stateNow(/* withPartialPass = */ false, stats.samples), stop);
        if (stop) {
            stats.interrupted = s0_ < target;
            break;
        }
    }
    stats.sppCompleted = s0_ - std::min(s0_, opt_.firstSample);
    // Splats are estimates per camera sample of the whole image: divide by samples per pixel taken.
    uint64_t pixelsTotal = uint64_t(film_.width()) * uint64_t(film_.height());
    film_.setSplatSppDouble(pixelsTotal > 0 ? double(stats.samples) / double(pixelsTotal) : 0.0);
    stats.nonFiniteDropped = nonFinite_.load();
    stats.firstNonFinite = firstNonFinite_;
    stats.seconds = st_.seconds + elapsed();
    return stats;
}

}  // namespace

RenderStats renderImage(const RenderContext& ctx, const Integrator& integrator, Film& film, const RenderOptions& opt) {
    return TileScheduler(ctx, integrator, film, opt).run();
}

}  // namespace tessera
