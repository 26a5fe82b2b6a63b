#pragma once
/// \file integrator.h
/// The integrator interface. An integrator estimates one camera sample at a time; the scheduler
/// (render/) owns tiles, threads and the film. One virtual call per camera sample is cheap next to
/// the path it traces (pbrt-v4 makes the same choice). Light tracing and BDPT reach pixels other than the
/// one being sampled through the SplatSink, which the scheduler merges deterministically.
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "accel/accel.h"
#include "core/sampler.h"
#include "scene/camera.h"
#include "scene/scene.h"

namespace tessera {

class SampleTrace;
class ThreadPool;

/// Everything a sample needs to read; shared by all threads.
struct RenderContext {
    const Scene& scene;
    const Accel& accel;
    const Camera& camera;
    int maxDepth = -1;  ///< maximum bounces, −1 = unlimited
    /// Set only by `--debug-pixel`'s replay (integrators/sample_trace.h); null in renders.
    SampleTrace* trace = nullptr;
};

/// Contributions to arbitrary pixels (light-tracing style). One sink per tile; entries are merged
/// into the film in tile order after each pass, so the image does not depend on thread timing.
/// A splat's value is the contribution of one camera-sample's worth of paths: the film divides the
/// accumulated splats by the number of samples per pixel.
class SplatSink {
public:
    struct Entry {
        uint32_t pixelIndex;
        Rgb value;
    };
    void splat(int width, int height, Vec2f raster, const Rgb& value) {
        int x = int(raster.x), y = int(raster.y);
        if (x < 0 || y < 0 || x >= width || y >= height) return;
        entries_.push_back({uint32_t(y) * uint32_t(width) + uint32_t(x), value});
    }
    std::vector<Entry>& entries() { return entries_; }
    const std::vector<Entry>& entries() const { return entries_; }
    void clear() { entries_.clear(); }

private:
    std::vector<Entry> entries_;
};

class Integrator {
public:
    virtual ~Integrator() = default;
    virtual std::string_view name() const = 0;
    /// Estimates the radiance reaching the camera through `raster` (a jittered position inside
    /// `pixel`). Returns the pixel's own estimate; may splat to other pixels.
    virtual Rgb sample(const RenderContext& ctx, Vec2i pixel, Vec2f raster, Sampler& sampler, SplatSink& splats) const = 0;

    /// What a pass's samples share, computed before them: the photon map of a photon-mapping
    /// integrator for sample indices [firstSample, firstSample + count). Called by the scheduler
    /// between passes (never while sample() runs), on the render's seed and sampler kind; the
    /// result must be a function of these arguments alone, so that resumed and merged renders
    /// repeat it exactly. Default: nothing to prepare.
    virtual void preparePass(const RenderContext& /*ctx*/, uint32_t /*firstSample*/, uint32_t /*count*/, uint64_t /*seed*/,
                             SamplerKind /*kind*/, ThreadPool& /*pool*/) const {}
    /// The most samples per pixel one pass may hold (what preparePass can prepare at once); 0 = any.
    virtual uint32_t maxPassSamples() const { return 0; }
};

/// Names accepted by createIntegrator.
std::vector<std::string> integratorNames();
/// Throws InputError on an unknown name.
std::unique_ptr<Integrator> createIntegrator(std::string_view name);
/// The integrator `settings.integrator` with the settings that tune it (sppm's photons).
std::unique_ptr<Integrator> createIntegrator(const RenderSettings& settings);

}  // namespace tessera
