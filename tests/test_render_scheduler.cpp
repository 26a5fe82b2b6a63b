// The renderer's own thread pool (core/thread_pool.h) and what the scheduler promises on top of it:
// every item once, a barrier between calls, exceptions reaching the caller, the caller's
// floating-point mode untouched. Run under ThreadSanitizer by tools/sanitize.sh tsan.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>

#include "core/thread_pool.h"
#include "integrators/integrator.h"
#include "render/renderer.h"
#include "test_helpers.h"

#if defined(__SSE__) || defined(__x86_64__)
#include <xmmintrin.h>
#define TESSERA_TEST_MXCSR 1
#endif

using namespace tessera;

TEST(Scheduler, PoolRunsEveryItemExactlyOnceForAnyThreadCount) {
    for (int threads : {1, 2, 3, 8}) {
        ThreadPool pool(threads);
        EXPECT_EQ(pool.threads(), threads);
        for (size_t count : {size_t(0), size_t(1), size_t(2), size_t(7), size_t(1000)}) {
            std::vector<std::atomic<int>> hits(count);
            pool.parallelFor(count, [&](size_t i) { hits[i].fetch_add(1, std::memory_order_relaxed); });
            for (size_t i = 0; i < count; ++i) ASSERT_EQ(hits[i].load(), 1) << "item " << i << " of " << count << ", " << threads << " threads";
        }
    }
    EXPECT_EQ(ThreadPool(0).threads(), hardwareThreads());
    EXPECT_GE(hardwareThreads(), 1);
}

TEST(Scheduler, PoolUsesSeveralThreadsAndSeparatesCallsByABarrier) {
    // Plain (non-atomic) writes in one call, read in the next: correct only if parallelFor returns
    // after every item and the next call starts after that (TSan reports the race otherwise).
    ThreadPool pool(4);
    std::vector<int> a(4096, 0), b(4096, 0);
    std::mutex idsMutex;
    std::set<std::thread::id> ids;
    for (int round = 0; round < 20; ++round) {
        pool.parallelFor(a.size(), [&](size_t i) { a[i] = int(i) + round; });
        pool.parallelFor(a.size(), [&](size_t i) {
            b[i] = a[(i * 7919) % a.size()];
            if (i % 64 == 0) {
                // Sleep a little so every worker gets items even on a loaded machine.
                std::this_thread::sleep_for(std::chrono::microseconds(200));
                std::lock_guard<std::mutex> lock(idsMutex);
                ids.insert(std::this_thread::get_id());
            }
        });
        for (size_t i = 0; i < b.size(); ++i) ASSERT_EQ(b[i], int((i * 7919) % a.size()) + round);
    }
    EXPECT_GE(ids.size(), 2u) << "the pool never ran items on a second thread";
}

TEST(Scheduler, PoolRethrowsTheWorkersExceptionAndStaysUsable) {
    for (int threads : {1, 3}) {
        ThreadPool pool(threads);
        std::atomic<int> ran{0};
        EXPECT_THROW(pool.parallelFor(10000, [&](size_t i) {
            ran.fetch_add(1);
            if (i == 5) throw std::runtime_error("tile 5 failed");
        }), std::runtime_error);
        // Items not yet claimed when the exception arrives are skipped. Exact with the caller's
        // thread alone (items run in order); with more, how many ran depends on thread timing.
        if (threads == 1) {
            EXPECT_EQ(ran.load(), 6);
        }
        try {
            pool.parallelFor(4, [](size_t i) {
                if (i == 3) throw std::invalid_argument("item 3");
            });
            FAIL() << "no exception";
        } catch (const std::invalid_argument& e) {
            EXPECT_STREQ(e.what(), "item 3");
        }
        std::atomic<int> after{0};
        pool.parallelFor(100, [&](size_t) { after.fetch_add(1); });
        EXPECT_EQ(after.load(), 100) << threads << " threads";
    }
}

namespace {
/// An integrator that throws at one pixel: the exception must reach renderImage's caller.
class ThrowingIntegrator : public Integrator {
public:
    std::string_view name() const override { return "throwing"; }
    Rgb sample(const RenderContext&, Vec2i pixel, Vec2f, Sampler&, SplatSink&) const override {
        if (pixel.x == 13 && pixel.y == 17) throw std::runtime_error("bad pixel");
        return Rgb(0.5f);
    }
};
}  // namespace

TEST(Scheduler, RenderPropagatesIntegratorExceptionsAndRestoresFpMode) {
    Scene scene = test::closedSphere(Rgb(0.5f), Rgb(1.f), false);
    auto accel = createAccel("embree", scene.geometry);
    Camera camera(*scene.camera, 40, 40);
    RenderContext ctx{scene, *accel, camera, -1};
#if defined(TESSERA_TEST_MXCSR)
    const unsigned before = _mm_getcsr();
#endif
    for (int threads : {1, 3}) {
        Film film(40, 40);
        RenderOptions opt{.spp = 2, .threads = threads, .tileSize = 8};
        ThrowingIntegrator throwing;
        EXPECT_THROW(renderImage(ctx, throwing, film, opt), std::runtime_error) << threads << " threads";
        auto ptnee = createIntegrator("ptnee");
        RenderStats stats = renderImage(ctx, *ptnee, film, opt);
        EXPECT_EQ(stats.threads, threads);
        EXPECT_EQ(stats.sppCompleted, 2u);
#if defined(TESSERA_TEST_MXCSR)
        // The caller's thread renders tiles too, with FTZ/DAZ; its own mode must come back.
        EXPECT_EQ(_mm_getcsr() & 0x8040u, before & 0x8040u) << threads << " threads";
#endif
    }
}
