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
};

constexpr uint32_t kMaxPassSpp = 16;

}  // namespace

RenderStats renderImage(const RenderContext& ctx, const Integrator& integrator, Film& film, const RenderOptions& opt) {
    auto start = std::chrono::steady_clock::now();
    auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
    const int width = film.width(), height = film.height();
    const int ts = std::max(1, opt.tileSize);
    std::vector<Tile> tiles;
    for (int y = 0; y < height; y += ts)
        for (int x = 0; x < width; x += ts) tiles.push_back({x, y, std::min(x + ts, width), std::min(y + ts, height)});
    std::vector<SplatSink> splats(tiles.size());
    std::vector<uint8_t> tileDone(tiles.size(), 0);

    RenderState st = opt.resume ? *opt.resume : RenderState{};
    if (!st.tileDone.empty() && (st.tileDone.size() != tiles.size() || st.pendingSplats.size() != tiles.size()))
        throw std::invalid_argument("renderImage: the resumed state has " + std::to_string(st.tileDone.size()) +
                                    " tiles, the film " + std::to_string(tiles.size()));
    std::atomic<uint64_t> nonFinite{st.nonFinite};
    std::atomic<uint64_t> tilesRendered{0};
    std::mutex firstMutex;
    std::optional<SampleId> firstNonFinite = st.firstNonFinite;
    auto cancelled = [&] {
        return (opt.cancel && opt.cancel->load(std::memory_order_relaxed)) ||
               (opt.stopAfterTiles > 0 && tilesRendered.load(std::memory_order_relaxed) >= opt.stopAfterTiles);
    };

    RenderStats stats;
    // Our own pool, not TBB: its mutex/condition-variable hand-offs are visible to ThreadSanitizer,
    // so tools/sanitize.sh tests the scheduler that every build runs (writeup.md §10).
    ThreadPool pool(opt.threads);
    stats.threads = pool.threads();

    const bool timed = opt.timeLimitSeconds > 0.0;
    const uint32_t target = timed ? 0xffffffffu : uint32_t(std::max(0, opt.spp));
    uint32_t s0 = st.sppDone, passSpp = std::max(1u, st.passSpp);
    const uint32_t s0Session = s0;
    bool resumePartial = !st.tileDone.empty();
    stats.samples = st.samples;
    uint64_t pixelsTotal = uint64_t(width) * uint64_t(height);
    auto stateNow = [&](bool withPartialPass) {
        RenderState cp;
        cp.sppDone = s0;
        cp.passSpp = passSpp;
        cp.samples = stats.samples;
        cp.nonFinite = nonFinite.load();
        cp.seconds = st.seconds + elapsed();
        cp.firstNonFinite = firstNonFinite;
        if (withPartialPass) {
            cp.tileDone = tileDone;
            cp.pendingSplats.resize(tiles.size());
            for (size_t t = 0; t < tiles.size(); ++t)
                if (tileDone[t]) cp.pendingSplats[t] = splats[t].entries();
        }
        return cp;
    };

    while (s0 < target) {
        if (timed && s0 > s0Session && !resumePartial) {
            double used = elapsed(), perSpp = used / double(s0 - s0Session), left = opt.timeLimitSeconds - used;
            if (left <= 0.0) break;
            // Stop at a pass boundary: never start a pass predicted to overrun by more than one spp.
            passSpp = uint32_t(std::clamp(left / std::max(perSpp, 1e-9), 1.0, double(passSpp)));
        }
        uint32_t n = std::min(passSpp, target - s0);
        if (resumePartial) {
            // The pass the checkpoint stopped in: its finished tiles are in the film, their splats wait.
            tileDone = st.tileDone;
            for (size_t t = 0; t < tiles.size(); ++t) splats[t].entries() = std::move(st.pendingSplats[t]);
            resumePartial = false;
        } else {
            std::fill(tileDone.begin(), tileDone.end(), 0);
        }
        // One item per tile, claimed in tile order; parallelFor returns when the pass is done (the
        // barrier before the splat merge and the checkpoint). The interrupt flag is read before
        // every tile, so a stop request skips the tiles not yet started.
        pool.parallelFor(tiles.size(), [&](size_t t) {
            if (tileDone[t] || cancelled()) return;
            // FTZ/DAZ while the tile renders, restored after it (MXCSR is per thread, and the
            // caller's thread renders tiles too, then goes on to read and write images).
            ScopedFlushToZero ftz;
            const Tile& tile = tiles[t];
            SplatSink& sink = splats[t];
            uint64_t bad = 0;
            std::optional<SampleId> tileFirst;
            for (int y = tile.y0; y < tile.y1; ++y)
                for (int x = tile.x0; x < tile.x1; ++x)
                    for (uint32_t s = s0; s < s0 + n; ++s) {
                        Sampler sampler(Vec2i(x, y), s, opt.seed);
                        Vec2f raster = Vec2f(float(x), float(y)) + sampler.get2D();
                        size_t splatsBefore = sink.entries().size();
                        Rgb L = integrator.sample(ctx, Vec2i(x, y), raster, sampler, sink);
                        bool finite = isFinite(L);
                        if (finite) film.addSample(x, y, L);
                        else ++bad;
                        // Non-finite splats are dropped at the merge; note their sample here.
                        for (size_t k = splatsBefore; finite && k < sink.entries().size(); ++k)
                            finite = isFinite(sink.entries()[k].value);
                        SampleId id{x, y, s};
                        if (!finite && (!tileFirst || id < *tileFirst)) tileFirst = id;
                    }
            if (bad) nonFinite.fetch_add(bad, std::memory_order_relaxed);
            if (tileFirst) {
                std::lock_guard<std::mutex> lock(firstMutex);
                if (!firstNonFinite || *tileFirst < *firstNonFinite) firstNonFinite = tileFirst;
            }
            tileDone[t] = 1;
            tilesRendered.fetch_add(1, std::memory_order_relaxed);
            if (opt.progress) opt.progress->advance(uint64_t(tile.x1 - tile.x0) * uint64_t(tile.y1 - tile.y0) * n);
        });
        bool complete = std::all_of(tileDone.begin(), tileDone.end(), [](uint8_t d) { return d != 0; });
        // Stopped mid-pass: the checkpoint keeps this pass's splats unmerged (tile order, see above).
        if (!complete && opt.onPassEnd) opt.onPassEnd(film, stateNow(/* withPartialPass = */ true), true);
        // Merge splats in tile order: the sums then do not depend on which thread ran which tile.
        for (size_t t = 0; t < tiles.size(); ++t) {
            if (!tileDone[t]) continue;
            uint64_t tilePixels = uint64_t(tiles[t].x1 - tiles[t].x0) * uint64_t(tiles[t].y1 - tiles[t].y0);
            stats.samples += tilePixels * n;
            for (const SplatSink::Entry& e : splats[t].entries()) {
                if (isFinite(e.value)) film.addSplat(e.pixelIndex, e.value);
                else nonFinite.fetch_add(1, std::memory_order_relaxed);
            }
            splats[t].clear();
        }
        if (!complete) {
            stats.interrupted = true;
            break;
        }
        s0 += n;
        passSpp = std::min(kMaxPassSpp, passSpp * (s0 >= 2 ? 2u : 1u));
        bool stop = cancelled();
        if (opt.onPassEnd) opt.onPassEnd(film, stateNow(/* withPartialPass = */ false), stop);
        if (stop) {
            stats.interrupted = s0 < target;
            break;
        }
    }
    stats.sppCompleted = s0;
    // Splats are estimates per camera sample of the whole image: divide by samples per pixel taken.
    film.setSplatSppDouble(pixelsTotal > 0 ? double(stats.samples) / double(pixelsTotal) : 0.0);
    stats.nonFiniteDropped = nonFinite.load();
    stats.firstNonFinite = firstNonFinite;
    stats.seconds = st.seconds + elapsed();
    return stats;
}

}  // namespace tessera
