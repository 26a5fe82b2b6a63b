#include "view/preview.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "integrators/integrator.h"
#include "render/film.h"

namespace tessera::view {
namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

}  // namespace

PreviewSession::PreviewSession(const Scene& scene, const Accel& accel, const PreviewSettings& settings, const CameraDesc& camera,
                               const std::string& integrator)
    : scene_(scene), accel_(accel), settings_(settings), camera_(camera), integratorName_(integrator) {
    createIntegrator(integratorName_);  // an unknown name fails here, in the caller's thread
    thread_ = std::thread([this] { run(); });
}

PreviewSession::~PreviewSession() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        quit_ = true;
        cancel_.store(true);  // the pass in flight stops before its next tile
    }
    changed_.notify_all();
    thread_.join();
}

void PreviewSession::restartLocked() {
    ++generation_;
    cancel_.store(true);
}

void PreviewSession::setCamera(const CameraDesc& camera, bool moving) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        camera_ = camera;
        moving_ = moving;
        restartLocked();
    }
    changed_.notify_all();
}

void PreviewSession::setIntegrator(const std::string& name) {
    createIntegrator(name);  // validate before touching the session
    {
        std::lock_guard<std::mutex> lock(mutex_);
        integratorName_ = name;
        restartLocked();
    }
    changed_.notify_all();
}

void PreviewSession::reset() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        restartLocked();
    }
    changed_.notify_all();
}

std::shared_ptr<const PreviewFrame> PreviewSession::newFrame(uint64_t& version) const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (version_ <= version || !latest_) return nullptr;
    version = version_;
    return latest_;
}

std::shared_ptr<const PreviewFrame> PreviewSession::currentFullFrame() const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!latestFull_ || latestFull_->generation != generation_) return nullptr;
    return latestFull_;
}

PreviewCounters PreviewSession::counters() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return counters_;
}

std::string PreviewSession::integrator() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return integratorName_;
}

bool PreviewSession::waitForSpp(uint32_t spp, double timeoutSeconds) const {
    std::unique_lock<std::mutex> lock(mutex_);
    return published_.wait_for(lock, std::chrono::duration<double>(timeoutSeconds), [&] {
        return latestFull_ && latestFull_->generation == generation_ && latestFull_->spp >= spp;
    });
}

void PreviewSession::publish(std::shared_ptr<const PreviewFrame> frame) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (frame->reduced) {
            ++counters_.reducedFrames;
        } else {
            latestFull_ = frame;
            if (frame->spp == 1) counters_.firstFullFrameSeconds = frame->wallSeconds;
        }
        latest_ = std::move(frame);
        ++version_;
    }
    published_.notify_all();
}

void PreviewSession::run() {
    const int W = settings_.width, H = settings_.height;
    std::unique_ptr<Integrator> integrator;
    std::string integratorName;
    // The accumulation: its generation (0: none), film and scheduler state.
    uint64_t accGeneration = 0, reducedGeneration = 0;
    std::unique_ptr<Film> film;
    RenderState state;
    Clock::time_point restartTime = Clock::now();
    double samplesPerSecond = 0.0;  // latest measured rate, picks the reduction while moving
    int reduction = std::clamp(4, settings_.minReduction, settings_.maxReduction);

    for (;;) {
        CameraDesc desc;
        bool moving = false;
        uint64_t generation = 0;
        std::string name;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            changed_.wait(lock, [&] {
                if (quit_) return true;
                if (moving_) return generation_ != reducedGeneration;
                if (generation_ != accGeneration) return true;
                return settings_.sppLimit == 0 || state.sppDone < settings_.sppLimit;
            });
            if (quit_) return;
            // Lowered under the mutex that every restart raises it under, after reading nothing
            // stale: a change from here on raises it again and cancels this pass.
            cancel_.store(false);
            desc = camera_;
            moving = moving_;
            generation = generation_;
            name = integratorName_;
        }
        if (!integrator || name != integratorName) {
            integrator = createIntegrator(name);
            integratorName = name;
        }

        if (moving) {
            // A reduced frame: 1 spp at width/k x height/k, finished even if the camera changes
            // meanwhile (it is short, and it is the frame that follows the input).
            reducedGeneration = generation;
            accGeneration = 0;  // the camera moved: the next still frame starts a new accumulation
            if (samplesPerSecond > 0.0) {
                double pixelsAffordable = samplesPerSecond * settings_.movingFrameSeconds;
                int k = int(std::ceil(std::sqrt(double(W) * double(H) / std::max(pixelsAffordable, 1.0))));
                reduction = std::clamp(k, settings_.minReduction, settings_.maxReduction);
            }
            int w = std::max(1, W / reduction), h = std::max(1, H / reduction);
            Film small(w, h);
            Camera camera(desc, w, h);
            RenderContext ctx{scene_, accel_, camera, settings_.maxDepth};
            RenderOptions ro{.spp = 1, .threads = settings_.threads, .seed = settings_.seed, .sampler = settings_.sampler};
            auto t0 = Clock::now();
            RenderStats st = renderImage(ctx, *integrator, small, ro);
            double seconds = secondsSince(t0);
            if (seconds > 0.0) samplesPerSecond = double(st.samples) / seconds;
            auto frame = std::make_shared<PreviewFrame>();
            frame->width = w;
            frame->height = h;
            frame->rgba = small.rgba();
            frame->reduced = true;
            frame->reduction = reduction;
            frame->camera = desc;
            frame->integrator = integratorName;
            frame->generation = generation;
            frame->spp = 1;
            frame->samples = st.samples;
            frame->renderSeconds = frame->wallSeconds = seconds;
            frame->threads = st.threads;
            {
                std::lock_guard<std::mutex> lock(mutex_);
                counters_.lastReducedFrameSeconds = seconds;
            }
            publish(std::move(frame));
            continue;
        }

        if (generation != accGeneration) {
            film = std::make_unique<Film>(W, H);
            state = RenderState{};
            accGeneration = generation;
            restartTime = Clock::now();
            std::lock_guard<std::mutex> lock(mutex_);
            ++counters_.restarts;
            counters_.firstFullFrameSeconds.reset();
        }
        // One pass of 1 spp continuing the accumulation: samples sppDone of every pixel, exactly
        // the ones `render --spp N` takes at that index.
        Camera camera(desc, W, H);
        RenderContext ctx{scene_, accel_, camera, settings_.maxDepth};
        RenderOptions ro{.spp = int(state.sppDone + 1), .threads = settings_.threads, .seed = settings_.seed, .sampler = settings_.sampler};
        ro.cancel = &cancel_;
        ro.resume = &state;
        RenderStats st = renderImage(ctx, *integrator, *film, ro);
        if (st.interrupted) {
            // Abandoned mid-pass: the film holds part of a pass, so it is dropped with its camera.
            accGeneration = 0;
            std::lock_guard<std::mutex> lock(mutex_);
            ++counters_.passesAbandoned;
            continue;
        }
        state.sppDone = st.sppCompleted;
        state.passSpp = 1;
        state.samples = st.samples;
        state.nonFinite = st.nonFiniteDropped;
        state.seconds = st.seconds;
        state.firstNonFinite = st.firstNonFinite;
        if (st.seconds > 0.0) samplesPerSecond = double(st.samples) / st.seconds;

        auto frame = std::make_shared<PreviewFrame>();
        frame->width = W;
        frame->height = H;
        frame->rgba = film->rgba();
        frame->camera = desc;
        frame->integrator = integratorName;
        frame->generation = generation;
        frame->spp = state.sppDone;
        frame->samples = state.samples;
        frame->renderSeconds = state.seconds;
        frame->wallSeconds = secondsSince(restartTime);
        frame->nonFiniteDropped = state.nonFinite;
        frame->threads = st.threads;
        publish(std::move(frame));
    }
}

}  // namespace tessera::view
