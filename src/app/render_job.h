#pragma once
/// \file render_job.h
/// One render from settings to written images, shared by `tessera render` (one job) and `tessera
/// batch` (many jobs over scenes and acceleration structures loaded once): the job's settings, the
/// checks made before any time is spent (film memory, output paths, display transform,
/// integrator), and the run itself on an already-loaded scene and built acceleration structure
/// (progress, Ctrl-C, checkpoints, EXR + PNG written atomically, summary line).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "app/scene_options.h"
#include "integrators/integrator.h"
#include "io/display_transform.h"
#include "render/renderer.h"

namespace tessera {
class Accel;
}

namespace tessera::app {

/// Everything that decides one render besides the scene options: outputs, acceleration structure,
/// limits and checkpoints.
struct RenderJob : SceneOptions {
    std::string output;  ///< EXR path (empty: out/<scene>.exr)
    std::string png;     ///< PNG path (empty: the EXR path with .png)
    std::string accel;   ///< empty: embree
    std::string display = "sRGB", view = "Standard";
    std::string bdptStrategies;  ///< directory for the per-strategy debug images (empty: none)
    int threads = 0;
    double timeLimit = 0.0;  ///< > 0: render passes for this many seconds instead of a fixed spp
    bool quiet = false, noPng = false;
    double checkpointSeconds = -1.0;  ///< < 0: no checkpoints
    bool resume = false;
    uint64_t stopAfterTiles = 0;  ///< test hook (hidden option)
    /// "A:B": render only samples [A, B) of every pixel into a partial at `output` (default
    /// out/<scene>_A-B.partial) for `tessera merge` (render/partial.h), instead of an image.
    std::string samples;
};

/// The acceleration structure a job asks for ("embree" when it names none).
std::string accelName(const RenderJob& job);

/// Where the images go; `display` is set when a PNG is written.
struct OutputPaths {
    std::string exr, png;  ///< png empty: no PNG
    std::optional<io::DisplayTransform> display;
};

/// A job checked and ready to run: every problem that can be found without rendering has been
/// (InputError otherwise), so a bad path or display never costs a render.
struct JobPlan {
    RenderSettings settings;
    CameraDesc camera;
    OutputPaths out;
    std::unique_ptr<Integrator> integrator;
};

/// Checks the film memory, the output paths, the display transform and the integrator of `job`
/// rendered with `settings` from `camera` (and a sample range's bounds and options). For a sample
/// range, `out.exr` is the partial's path and no PNG is written.
JobPlan planRenderJob(const RenderJob& job, const RenderSettings& settings, const CameraDesc& camera);

struct RenderJobResult {
    RenderStats stats;
    std::string accel;          ///< the structure's name
    double buildSeconds = 0.0;  ///< its build time
    std::string checkpoint;     ///< the checkpoint left behind by an interrupted render (empty: none)
};

/// Renders `plan` over `scene` (whose environment options are applied) with `accel` (built over
/// its geometry), writes the images and prints the summary line unless quiet. `label` names the
/// render in progress lines ("render cornell-box"). Ctrl-C stops at the next tile and still writes
/// the images (stats.interrupted); the caller resets interruptFlag() when it wants a fresh start.
RenderJobResult runRenderJob(const RenderJob& job, const JobPlan& plan, const Scene& scene, const Accel& accel,
                             const std::string& label);

/// Camera samples per second of a render (0 when it took no time).
double samplesPerSecond(const RenderStats& stats);
/// "pixel (x,y) sample s".
std::string describe(const SampleId& id);

}  // namespace tessera::app
