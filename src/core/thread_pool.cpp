#include "core/thread_pool.h"

#if defined(__linux__)
#include <sched.h>
#endif

namespace tessera {

int hardwareThreads() {
#if defined(__linux__)
    cpu_set_t set;
    CPU_ZERO(&set);
    if (sched_getaffinity(0, sizeof(set), &set) == 0 && CPU_COUNT(&set) > 0) return CPU_COUNT(&set);
#endif
    unsigned n = std::thread::hardware_concurrency();
    return n > 0 ? int(n) : 1;
}

ThreadPool::ThreadPool(int threads) {
    int n = threads > 0 ? threads : hardwareThreads();
    workers_.reserve(size_t(n - 1));
    try {
        for (int i = 1; i < n; ++i) workers_.emplace_back([this] { workerLoop(); });
    } catch (...) {
        // Out of threads (std::system_error): join the ones started, or their std::thread
        // destructors would terminate the process, and report the failure to the caller.
        stopAndJoin();
        throw;
    }
}

ThreadPool::~ThreadPool() { stopAndJoin(); }

void ThreadPool::stopAndJoin() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : workers_) t.join();
    workers_.clear();
}

void ThreadPool::drain(Job& job) {
    for (;;) {
        if (job.failed.load(std::memory_order_relaxed)) return;
        size_t i = job.next.fetch_add(1, std::memory_order_relaxed);
        if (i >= job.count) return;
        try {
            (*job.body)(i);
        } catch (...) {
            std::lock_guard<std::mutex> lock(job.errorMutex);
            if (!job.error) job.error = std::current_exception();
            job.failed.store(true, std::memory_order_relaxed);
        }
    }
}

void ThreadPool::workerLoop() {
    uint64_t seen = 0;
    for (;;) {
        Job* job = nullptr;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
            if (stop_) return;
            seen = generation_;
            job = job_;
        }
        drain(*job);
        bool last = false;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            last = --busy_ == 0;
        }
        if (last) done_.notify_one();
    }
}

void ThreadPool::parallelFor(size_t count, const std::function<void(size_t)>& body) {
    if (count == 0) return;
    Job job;
    job.body = &body;
    job.count = count;
    // Waking the workers costs more than one item: run it here.
    bool wake = !workers_.empty() && count > 1;
    if (wake) {
        {
            // The lock orders everything the caller wrote before this call before the workers'
            // reads (and releasing it after busy_ reaches 0 orders their writes before ours).
            std::lock_guard<std::mutex> lock(mutex_);
            job_ = &job;
            busy_ = int(workers_.size());
            ++generation_;
        }
        wake_.notify_all();
    }
    drain(job);
    if (wake) {
        std::unique_lock<std::mutex> lock(mutex_);
        // Every worker must leave the job before it goes out of scope, even one that woke late
        // and found nothing left to claim.
        done_.wait(lock, [&] { return busy_ == 0; });
        job_ = nullptr;
    }
    if (job.error) std::rethrow_exception(job.error);
}

}  // namespace tessera
