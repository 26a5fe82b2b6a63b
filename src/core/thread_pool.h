#pragma once
/// \file thread_pool.h
/// The renderer's own worker threads (pbrt-v4 and Mitsuba run their own pools too). A pool holds
/// N − 1 std::threads; parallelFor runs on all of them plus the calling thread and returns only
/// when every item is done, so consecutive calls are separated by a barrier. Items are claimed from
/// one atomic counter in index order: no work stealing, no per-split copies of the loop body, and
/// every hand-off is a std::mutex/std::condition_variable that ThreadSanitizer sees (Debian's
/// libtbb is not instrumented, so under TSan its task hand-offs looked like races: writeup, "How correctness is tested").
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace tessera {

/// Threads this process may run on (its CPU affinity mask, as TBB's default concurrency; at least 1).
int hardwareThreads();

class ThreadPool {
public:
    /// `threads` in total, the caller of parallelFor included; ≤ 0 means hardwareThreads().
    explicit ThreadPool(int threads);
    /// Joins the workers. Must not run while a parallelFor is in progress.
    ~ThreadPool();
    ThreadPool(const ThreadPool&) = delete;
    ThreadPool& operator=(const ThreadPool&) = delete;

    int threads() const { return int(workers_.size()) + 1; }

    /// Calls body(i) once for every i in [0, count), on the pool's threads and the caller's, and
    /// returns when all calls have returned. Items start in increasing order of i (which thread
    /// takes which is timing-dependent). If a call throws, items not yet started are skipped and the
    /// first exception caught is rethrown here once every thread has stopped. One caller at a time;
    /// body must not call parallelFor on the same pool.
    void parallelFor(size_t count, const std::function<void(size_t)>& body);

private:
    struct Job {
        const std::function<void(size_t)>* body = nullptr;
        size_t count = 0;
        std::atomic<size_t> next{0};
        std::atomic<bool> failed{false};
        std::mutex errorMutex;
        std::exception_ptr error;
    };
    static void drain(Job& job);
    void workerLoop();
    void stopAndJoin();

    std::vector<std::thread> workers_;
    std::mutex mutex_;
    std::condition_variable wake_;  ///< a new job (generation_ changed) or stop_
    std::condition_variable done_;  ///< busy_ reached 0
    Job* job_ = nullptr;            ///< the job of the current generation (guarded by mutex_)
    uint64_t generation_ = 0;       ///< counts jobs; each worker runs each generation once
    int busy_ = 0;                  ///< workers still on the current job
    bool stop_ = false;
};

}  // namespace tessera
