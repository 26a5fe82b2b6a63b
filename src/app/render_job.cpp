/// \file render_job.cpp
#include "app/render_job.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "accel/accel.h"
#include "app/commands.h"
#include "core/error.h"
#include "core/fnv1a.h"
#include "core/version.h"
#include "integrators/bdpt.h"
#include "io/image_output.h"
#include "render/checkpoint.h"
#include "render/interrupt.h"
#include "render/partial.h"

namespace tessera::app {
namespace {

/// `--bdpt-strategies DIR` (pbrt's visualizestrategies): one EXR per strategy (s, t), weighted and
/// unweighted, for paths of at most maxDepth + 2 vertices (5 when the depth is unlimited). Each image
/// is a full re-render with the same seed that keeps one strategy, so the weighted images of all
/// strategies sum to the bdpt image rendered with the same --max-depth.
void writeBdptStrategyImages(const RenderJob& a, const RenderSettings& s, const RenderContext& ctx, RenderOptions ro,
                             const io::Metadata& md) {
    int maxVertices = s.maxDepth >= 0 ? s.maxDepth + 2 : 5;
    RenderContext limited = ctx;
    limited.maxDepth = maxVertices - 2;
    ro.progress = nullptr;
    // Fresh renders of their own: no resumed state, no checkpoints, no test stop.
    ro.resume = nullptr;
    ro.onPassEnd = nullptr;
    ro.stopAfterTiles = 0;
    for (int n = 2; n <= maxVertices; ++n)
        for (int t = 1; t <= n; ++t) {
            int sLight = n - t;
            for (bool weighted : {true, false}) {
                BdptSettings bs;
                bs.onlyS = sLight;
                bs.onlyT = t;
                bs.unweighted = !weighted;
                BdptIntegrator integrator(bs);
                Film film(s.width, s.height);
                renderImage(limited, integrator, film, ro);
                std::string path = a.bdptStrategies + "/bdpt_s" + std::to_string(sLight) + "_t" + std::to_string(t) +
                                   (weighted ? "_weighted.exr" : "_unweighted.exr");
                io::Metadata m = md;
                m.push_back({"tessera:bdpt_strategy", "s=" + std::to_string(sLight) + " t=" + std::to_string(t)});
                m.push_back({"tessera:bdpt_weighted", weighted ? "true" : "false"});
                std::vector<float> rgba = film.rgba();
                io::writeExr(path, s.width, s.height, rgba.data(), m);
            }
        }
}

/// Every setting that decides the pixels of a render (and so must match to resume it). The
/// acceleration structure and the thread count are left out: they do not change the image.
CheckpointHeader checkpointHeader(const RenderJob& a, const RenderSettings& s, const CameraDesc& cam, const Integrator& integrator,
                                  int tileSize) {
    std::string camera;
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) camera += exactFloat(cam.cameraToWorld[c][r]) + ",";
    camera += exactFloat(cam.yfov) + "," + exactFloat(cam.apertureRadius) + "," + exactFloat(cam.focusDistance);
    CheckpointHeader header = {
        {"renderer", std::string("tessera ") + versionString() + " (" + gitRevision() + ")"},
        {"scene_hash", fnv1a64OfFile(a.scene)},
        {"integrator", std::string(integrator.name())},
        {"seed", std::to_string(s.seed)},
        {"sampler", std::string(samplerName(s.sampler))},
        {"resolution", std::to_string(s.width) + "x" + std::to_string(s.height)},
        {"spp_target", a.timeLimit > 0 ? "time-bounded" : std::to_string(s.spp)},
        {"max_depth", std::to_string(s.maxDepth)},
        {"camera", camera},
        {"tile_size", std::to_string(tileSize)},
    };
    for (const auto& [key, value] : photonSettings(s)) header.push_back({key, value});
    // The command line's environment changes the pixels without changing the scene file.
    if (!a.env.empty() || a.envRotate || a.envIntensity)
        header.push_back({"environment", a.env + (a.env.empty() || !std::filesystem::exists(a.env) ? "" : " " + fnv1a64OfFile(a.env)) +
                                             " rotate " + (a.envRotate ? std::to_string(*a.envRotate) : "-") + " intensity " +
                                             (a.envIntensity ? std::to_string(*a.envIntensity) : "-")});
    return header;
}

OutputPaths outputPaths(const RenderJob& a) {
    OutputPaths o;
    if (!a.samples.empty()) {
        SampleRange range = parseSampleRange(a.samples, "--samples");
        o.exr = a.output.empty() ? "out/" + stem(a.scene) + "_" + std::to_string(range.begin) + "-" + std::to_string(range.end) + ".partial"
                                 : a.output;
        return o;
    }
    o.exr = a.output.empty() ? "out/" + stem(a.scene) + ".exr" : a.output;
    o.png = a.noPng ? "" : (a.png.empty() ? std::filesystem::path(o.exr).replace_extension(".png").string() : a.png);
    if (!o.png.empty()) o.display.emplace(a.display, a.view);
    return o;
}

/// `--checkpoint SEC` and `--resume`: OUT.exr.ckpt beside the image, written every SEC seconds (at
/// pass boundaries) and whenever the render stops early; --resume continues one and keeps it up to
/// date. Must outlive the render it is attached to.
class Checkpoints {
public:
    Checkpoints(const RenderJob& a, const std::string& exrPath, CheckpointHeader header)
        : path_(exrPath + ".ckpt"), enabled_(a.checkpointSeconds >= 0.0 || a.resume), everySeconds_(a.checkpointSeconds),
          header_(std::move(header)) {}

    /// With --resume, loads the checkpoint into `film` and `ro`; when enabled, has `ro` write them.
    void attach(const RenderJob& a, Film& film, RenderOptions& ro) {
        if (a.resume) {
            resumed_ = readCheckpoint(path_, header_, film);
            ro.resume = &resumed_;
            if (!a.quiet)
                std::cerr << "tessera: resuming " << path_ << " at " << resumed_.sppDone << " spp"
                          << (resumed_.tileDone.empty() ? "" : " (inside a pass)") << std::endl;
        }
        last_ = std::chrono::steady_clock::now();
        if (enabled_) ro.onPassEnd = [this](const Film& f, const RenderState& state, bool interrupted) { write(f, state, interrupted); };
    }
    /// A finished render leaves nothing to resume: a stale checkpoint would only mislead.
    void finish(const RenderStats& stats) const {
        if (!enabled_ || stats.interrupted) return;
        std::error_code ignored;
        std::filesystem::remove(path_, ignored);
    }
    bool enabled() const { return enabled_; }
    const std::string& path() const { return path_; }
    /// Camera samples the resumed checkpoint had taken (0 without --resume).
    uint64_t samplesResumed() const { return resumed_.samples; }

private:
    void write(const Film& f, const RenderState& state, bool interrupted) {
        double since = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_).count();
        if (!interrupted && since < everySeconds_) return;
        try {
            writeCheckpoint(path_, header_, f, state);
        } catch (const InputError& e) {
            // Losing a checkpoint must not lose the render itself.
            printWarning(e.what());
        }
        last_ = std::chrono::steady_clock::now();
    }

    std::string path_;
    bool enabled_;
    double everySeconds_;
    CheckpointHeader header_;
    RenderState resumed_;
    std::chrono::steady_clock::time_point last_;
};

/// The closing progress line, and the warning that names the first non-finite sample.
void printSummary(ProgressReporter& progress, const RenderStats& stats, const OutputPaths& out) {
    std::ostringstream summary;
    summary << stats.sppCompleted << " spp in " << formatDuration(stats.seconds) << " (" << samplesPerSecond(stats) / 1e6
            << " M samples/s, " << stats.threads << " threads)" << (stats.interrupted ? ", INTERRUPTED" : "") << " -> "
            << out.exr << (out.png.empty() ? "" : ", " + out.png);
    progress.done(summary.str());
    if (stats.nonFiniteDropped > 0) {
        std::string where;
        if (stats.firstNonFinite) {
            const SampleId& f = *stats.firstNonFinite;
            where = "; first non-finite sample at " + describe(f) + " - replay with --debug-pixel " + std::to_string(f.x) + "," +
                    std::to_string(f.y) + "," + std::to_string(f.sample);
        }
        printWarning(std::to_string(stats.nonFiniteDropped) + " non-finite sample(s) were dropped" + where);
    }
}

/// `--samples A:B`: samples [A, B) of every pixel into a partial (render/partial.h), no image.
RenderStats renderSampleRange(const RenderJob& a, const JobPlan& plan, const RenderContext& ctx, const Accel& accel,
                              const std::string& label) {
    const RenderSettings& s = plan.settings;
    SampleRange range = parseSampleRange(a.samples, "--samples");
    RenderOptions ro{.spp = int(range.end), .firstSample = range.begin, .threads = a.threads, .seed = s.seed, .sampler = s.sampler};
    InterruptGuard guard;
    ro.cancel = &interruptFlag();
    ProgressReporter progress(label + " samples " + range.str(), uint64_t(s.width) * uint64_t(s.height) * (range.end - range.begin),
                              0.0, a.quiet);
    ro.progress = &progress;
    Film film(s.width, s.height);
    RenderStats stats = renderImage(ctx, *plan.integrator, film, ro);
    if (stats.interrupted) {
        progress.done("samples " + range.str() + " INTERRUPTED: no partial written");
        return stats;
    }
    CheckpointHeader header = checkpointHeader(a, s, plan.camera, *plan.integrator, ro.tileSize);
    header.push_back({"scene", a.scene});
    header.push_back({"accel", std::string(accel.name())});
    writePartial(plan.out.exr, header, range, film, stats);
    progress.done("samples " + range.str() + " in " + formatDuration(stats.seconds) + " (" + std::to_string(samplesPerSecond(stats) / 1e6) +
                  " M samples/s, " + std::to_string(stats.threads) + " threads) -> " + plan.out.exr);
    return stats;
}

}  // namespace

double samplesPerSecond(const RenderStats& stats) { return stats.seconds > 0 ? double(stats.samples) / stats.seconds : 0.0; }

std::string accelName(const RenderJob& job) { return job.accel.empty() ? "embree" : job.accel; }

std::string describe(const SampleId& id) {
    return "pixel (" + std::to_string(id.x) + "," + std::to_string(id.y) + ") sample " + std::to_string(id.sample);
}

JobPlan planRenderJob(const RenderJob& job, const RenderSettings& settings, const CameraDesc& camera) {
    checkFilmFits(job, settings);
    if (!job.samples.empty()) {
        SampleRange range = parseSampleRange(job.samples, "--samples");
        if (job.timeLimit > 0 || job.resume || job.checkpointSeconds >= 0 || !job.bdptStrategies.empty())
            throw InputError("--samples renders a fixed sample range: not with --time, --checkpoint, --resume or --bdpt-strategies");
        if (range.end > uint32_t(settings.spp))
            throw InputError("--samples " + range.str() + " goes past the render's " + std::to_string(settings.spp) +
                             " spp (give the total with --spp N)");
    }
    JobPlan plan{settings, camera, outputPaths(job), nullptr};
    plan.integrator = createIntegrator(settings);
    return plan;
}

RenderJobResult runRenderJob(const RenderJob& a, const JobPlan& plan, const Scene& scene, const Accel& accel,
                             const std::string& label) {
    const RenderSettings& s = plan.settings;
    const Integrator& integrator = *plan.integrator;
    const OutputPaths& out = plan.out;
    Camera camera(plan.camera, s.width, s.height);
    RenderContext ctx{scene, accel, camera, s.maxDepth};
    if (!a.samples.empty()) return RenderJobResult{renderSampleRange(a, plan, ctx, accel, label), std::string(accel.name()),
                                                   accel.stats().buildSeconds, ""};

    Film film(s.width, s.height);
    RenderOptions ro{.spp = s.spp, .timeLimitSeconds = a.timeLimit, .threads = a.threads, .seed = s.seed, .sampler = s.sampler};
    ro.stopAfterTiles = a.stopAfterTiles;
    Checkpoints checkpoints(a, out.exr, checkpointHeader(a, s, plan.camera, integrator, ro.tileSize));
    checkpoints.attach(a, film, ro);

    InterruptGuard guard;
    ro.cancel = &interruptFlag();
    uint64_t total = a.timeLimit > 0 ? 0 : uint64_t(s.width) * uint64_t(s.height) * uint64_t(s.spp);
    total -= std::min(total, checkpoints.samplesResumed());
    ProgressReporter progress(label, total, a.timeLimit, a.quiet);
    ro.progress = &progress;
    RenderStats stats = renderImage(ctx, integrator, film, ro);

    io::Metadata md = imageMetadata(a.scene, s,
                                    ImageFacts{.integrator = std::string(integrator.name()), .accel = std::string(accel.name()),
                                               .spp = stats.sppCompleted, .samples = stats.samples,
                                               .nonFiniteDropped = stats.nonFiniteDropped, .seconds = stats.seconds,
                                               .threads = stats.threads, .interrupted = stats.interrupted, .resumed = a.resume});
    if (stats.firstNonFinite) md.push_back({"tessera:first_nonfinite", describe(*stats.firstNonFinite)});
    if (scene.environment)
        md.push_back({"tessera:environment", scene.environment->source + " rotation " + std::to_string(scene.environment->rotationDeg) +
                                                 " intensity " + std::to_string(scene.environment->intensity)});
    std::vector<float> rgba = film.rgba();
    io::writeExr(out.exr, s.width, s.height, rgba.data(), md);
    if (out.display) io::writePng(out.png, s.width, s.height, rgba.data(), *out.display, md);
    checkpoints.finish(stats);
    if (!a.bdptStrategies.empty() && !stats.interrupted) writeBdptStrategyImages(a, s, ctx, ro, md);

    printSummary(progress, stats, out);
    RenderJobResult result{stats, std::string(accel.name()), accel.stats().buildSeconds, ""};
    if (checkpoints.enabled() && stats.interrupted) result.checkpoint = checkpoints.path();
    return result;
}

}  // namespace tessera::app
