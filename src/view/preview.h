#pragma once
/// \file preview.h
/// The progressive preview behind `tessera view`: a render thread that runs the batch scheduler
/// (render/renderer.h) one pass at a time and publishes each finished frame.
///
/// - Still camera: passes of 1 sample per pixel at full resolution accumulate into one film,
///   resumed from the previous pass's RenderState, so after N passes the film holds exactly the
///   samples 0..N-1 of every pixel that `tessera render --spp N` takes (same seeds, same per-pixel
///   summation order: bit-identical for pt and ptnee; lt/bdpt merge splats in another order,
///   equal within rounding).
/// - Camera (or integrator) change: the generation counter moves and the cancel flag is raised, so
///   a full-resolution pass in flight stops before its next tile and is thrown away; accumulation
///   restarts from 0 spp.
/// - Moving camera: frames of 1 spp at a reduced resolution (1/k² of the pixels, k chosen from the
///   measured sample rate so a frame takes about `movingFrameSeconds`), each with the newest camera.
///   These are not cancelled: each is short by construction and is what lets the view follow.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "accel/accel.h"
#include "render/renderer.h"
#include "scene/scene.h"

namespace tessera::view {

struct PreviewSettings {
    int width = 0, height = 0;  ///< full resolution
    int threads = 0;            ///< as render's --threads (0: all cores)
    uint64_t seed = 0;
    SamplerKind sampler = kDefaultSampler;
    int maxDepth = -1;
    uint32_t sppLimit = 0;      ///< stop refining at this many spp (0: never)
    double movingFrameSeconds = 1.0 / 30.0;  ///< target time of a reduced-resolution frame
    int minReduction = 2, maxReduction = 8;  ///< bounds of k (the frame has width/k x height/k pixels)
};

/// One published image: linear RGBA as Film::rgba() gives it.
struct PreviewFrame {
    int width = 0, height = 0;
    std::vector<float> rgba;
    bool reduced = false;       ///< a moving-camera frame at 1/reduction of each side
    int reduction = 1;
    CameraDesc camera;
    std::string integrator;
    uint64_t generation = 0;    ///< camera/integrator generation it was rendered for
    uint32_t spp = 0;           ///< full-resolution: samples per pixel accumulated so far
    uint64_t samples = 0;       ///< camera samples accumulated since the restart
    double renderSeconds = 0.0; ///< scheduler time of those samples
    double wallSeconds = 0.0;   ///< wall time from the restart to this frame (all overheads included)
    uint64_t nonFiniteDropped = 0;
    int threads = 0;
};

/// Counters for the status line, the benchmark and the tests.
struct PreviewCounters {
    uint64_t restarts = 0;          ///< accumulations started (the first one included)
    uint64_t passesAbandoned = 0;   ///< full-resolution passes cancelled mid-way by a change
    uint64_t reducedFrames = 0;     ///< moving-camera frames published
    double lastReducedFrameSeconds = 0.0;
    std::optional<double> firstFullFrameSeconds;  ///< restart → first full-resolution frame, of the latest restart
};

class PreviewSession {
public:
    /// Starts the render thread with `camera` and `integrator` (a name accepted by createIntegrator).
    PreviewSession(const Scene& scene, const Accel& accel, const PreviewSettings& settings, const CameraDesc& camera,
                   const std::string& integrator);
    ~PreviewSession();
    PreviewSession(const PreviewSession&) = delete;
    PreviewSession& operator=(const PreviewSession&) = delete;

    /// A new camera: restarts accumulation at once (a full-resolution pass in flight is abandoned
    /// before its next tile). `moving`: render reduced-resolution frames until a call with false.
    void setCamera(const CameraDesc& camera, bool moving);
    /// Switches integrator (a name accepted by createIntegrator; throws InputError otherwise) and restarts.
    void setIntegrator(const std::string& name);
    /// Restarts accumulation with the same camera.
    void reset();

    /// The newest frame if its version is above `version` (then updates `version`), else null.
    std::shared_ptr<const PreviewFrame> newFrame(uint64_t& version) const;
    /// The newest full-resolution frame of the current generation (for saving), else null.
    std::shared_ptr<const PreviewFrame> currentFullFrame() const;
    PreviewCounters counters() const;
    std::string integrator() const;
    /// Blocks until the current generation has `spp` samples per pixel (or the limit), or `timeoutSeconds` passed.
    bool waitForSpp(uint32_t spp, double timeoutSeconds) const;

private:
    void run();
    /// Raises the generation and the cancel flag (mutex_ held).
    void restartLocked();
    void publish(std::shared_ptr<const PreviewFrame> frame);

    const Scene& scene_;
    const Accel& accel_;
    const PreviewSettings settings_;

    mutable std::mutex mutex_;
    std::condition_variable changed_;           ///< wakes the render thread
    mutable std::condition_variable published_; ///< wakes waitForSpp
    CameraDesc camera_;
    std::string integratorName_;
    bool moving_ = false, quit_ = false;
    uint64_t generation_ = 1;
    std::atomic<bool> cancel_{false};

    // Published state (under mutex_).
    std::shared_ptr<const PreviewFrame> latest_, latestFull_;
    uint64_t version_ = 0;
    PreviewCounters counters_;

    std::thread thread_;
};

}  // namespace tessera::view
