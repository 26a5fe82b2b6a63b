/// \file render_command.cpp
/// `tessera render SCENE`: load, build the acceleration structure, render, write EXR + PNG.
#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>

#include "accel/accel.h"
#include "app/commands.h"
#include "app/scene_options.h"
#include "core/error.h"
#include "core/fnv1a.h"
#include "core/version.h"
#include "integrators/bdpt.h"
#include "integrators/integrator.h"
#include "io/display_transform.h"
#include "io/image_output.h"
#include "render/checkpoint.h"
#include "render/debug_pixel.h"
#include "render/interrupt.h"
#include "render/renderer.h"
#include "scene/gltf_loader.h"

namespace tessera::app {
namespace {

struct RenderArgs : SceneOptions {
    std::string output, png, accel, display = "sRGB", view = "Standard";
    std::string bdptStrategies;  ///< directory for the per-strategy debug images (empty: none)
    std::string debugPixel;  ///< "x,y,s": replay one sample with a trace instead of rendering
    int threads = 0;
    double timeLimit = 0.0;
    bool quiet = false, json = false, noPng = false;
    double checkpointSeconds = -1.0;  ///< < 0: no checkpoints
    bool resume = false;
    uint64_t stopAfterTiles = 0;      ///< test hook (hidden option)
};



/// `--bdpt-strategies DIR` (pbrt's visualizestrategies): one EXR per strategy (s, t), weighted and
/// unweighted, for paths of at most maxDepth + 2 vertices (5 when the depth is unlimited). Each image
/// is a full re-render with the same seed that keeps one strategy, so the weighted images of all
/// strategies sum to the bdpt image rendered with the same --max-depth.
void writeBdptStrategyImages(const RenderArgs& a, const RenderSettings& s, const RenderContext& ctx, RenderOptions ro,
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

/// Hexadecimal float: the exact bits, so a camera changed in the last digit is a different camera.
std::string exact(float v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%a", double(v));
    return buf;
}

/// Every setting that decides the pixels of a render (and so must match to resume it). The
/// acceleration structure and the thread count are left out: they do not change the image.
CheckpointHeader checkpointHeader(const RenderArgs& a, const RenderSettings& s, const CameraDesc& cam, const Integrator& integrator,
                                  int tileSize) {
    std::string camera;
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) camera += exact(cam.cameraToWorld[c][r]) + ",";
    camera += exact(cam.yfov) + "," + exact(cam.apertureRadius) + "," + exact(cam.focusDistance);
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
    // The command line's environment changes the pixels without changing the scene file.
    if (!a.env.empty() || a.envRotate || a.envIntensity)
        header.push_back({"environment", a.env + (a.env.empty() || !std::filesystem::exists(a.env) ? "" : " " + fnv1a64OfFile(a.env)) +
                                             " rotate " + (a.envRotate ? std::to_string(*a.envRotate) : "-") + " intensity " +
                                             (a.envIntensity ? std::to_string(*a.envIntensity) : "-")});
    return header;
}

/// "x,y,s" → the sample to replay; checked against the image size.
SampleId parseDebugPixel(const std::string& text, int width, int height) {
    std::vector<float> v = parseNumbers(text, "--debug-pixel");
    if (v.size() != 3 || v[0] != std::floor(v[0]) || v[1] != std::floor(v[1]) || v[2] != std::floor(v[2]) || v[0] < 0 ||
        v[1] < 0 || v[2] < 0 || v[0] >= float(width) || v[1] >= float(height) || v[2] > 4e9f)
        throw InputError("--debug-pixel needs x,y,s: a pixel inside the " + std::to_string(width) + "x" + std::to_string(height) +
                         " image and a sample index >= 0, got '" + text + "'");
    return SampleId{int(v[0]), int(v[1]), uint32_t(v[2])};
}

std::string describe(const SampleId& id) {
    return "pixel (" + std::to_string(id.x) + "," + std::to_string(id.y) + ") sample " + std::to_string(id.sample);
}





/// Where the images go; `display` is set when a PNG is written (checked before the render starts).
struct OutputPaths {
    std::string exr, png;  ///< png empty: no PNG
    std::optional<io::DisplayTransform> display;
};

OutputPaths outputPaths(const RenderArgs& a) {
    OutputPaths o;
    o.exr = a.output.empty() ? "out/" + stem(a.scene) + ".exr" : a.output;
    o.png = a.noPng ? "" : (a.png.empty() ? std::filesystem::path(o.exr).replace_extension(".png").string() : a.png);
    if (!o.png.empty()) o.display.emplace(a.display, a.view);
    return o;
}

/// `--debug-pixel x,y,s`: replays one sample with a trace on stderr and prints its radiance.
int runDebugPixel(const RenderArgs& a, const RenderContext& ctx, const Integrator& integrator, const RenderSettings& s) {
    SampleId id = parseDebugPixel(a.debugPixel, s.width, s.height);
    SampleReplay r = replaySample(ctx, integrator, id, s.seed, s.sampler, std::cerr);
    if (a.json) {
        nlohmann::json splats = nlohmann::json::array();
        for (const SplatSink::Entry& e : r.splats) splats.push_back({e.pixelIndex, {e.value.r, e.value.g, e.value.b}});
        // Non-finite floats become null in JSON: "finite" says which.
        std::cout << nlohmann::json{{"pixel", {id.x, id.y}}, {"sample", id.sample}, {"seed", s.seed},
                                    {"sampler", samplerName(s.sampler)}, {"radiance", {r.radiance.r, r.radiance.g, r.radiance.b}}, {"finite", r.finite},
                                    {"rays", r.rays}, {"trace_records", r.vertices}, {"splats", splats}}.dump()
                  << std::endl;
    } else {
        std::printf("%s: radiance %.9g %.9g %.9g%s\n", describe(id).c_str(), double(r.radiance.r), double(r.radiance.g),
                    double(r.radiance.b), r.finite ? "" : " (NON-FINITE)");
    }
    return 0;
}

/// `--checkpoint SEC` and `--resume`: OUT.exr.ckpt beside the image, written every SEC seconds (at
/// pass boundaries) and whenever the render stops early; --resume continues one and keeps it up to
/// date. Must outlive the render it is attached to.
class Checkpoints {
public:
    Checkpoints(const RenderArgs& a, const std::string& exrPath, CheckpointHeader header)
        : path_(exrPath + ".ckpt"), enabled_(a.checkpointSeconds >= 0.0 || a.resume), everySeconds_(a.checkpointSeconds),
          header_(std::move(header)) {}

    /// With --resume, loads the checkpoint into `film` and `ro`; when enabled, has `ro` write them.
    void attach(const RenderArgs& a, Film& film, RenderOptions& ro) {
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


double samplesPerSecond(const RenderStats& stats) { return stats.seconds > 0 ? double(stats.samples) / stats.seconds : 0.0; }

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

/// `--json`: the run's figures as one JSON object on stdout.
void printJson(const RenderArgs& a, const RenderSettings& s, const Integrator& integrator, const Accel& accel,
               const RenderStats& stats, const OutputPaths& out, const Checkpoints& checkpoints) {
    nlohmann::json j = {
        {"scene", a.scene},
        {"integrator", std::string(integrator.name())},
        {"accel", std::string(accel.name())},
        {"spp", stats.sppCompleted},
        {"samples", stats.samples},
        {"seconds", stats.seconds},
        {"build_seconds", accel.stats().buildSeconds},
        {"resolution", {s.width, s.height}},
        {"threads", stats.threads},
        {"seed", s.seed},
        {"sampler", samplerName(s.sampler)},
        {"outputs", out.png.empty() ? nlohmann::json{{"exr", out.exr}} : nlohmann::json{{"exr", out.exr}, {"png", out.png}}},
        {"samples_per_second", samplesPerSecond(stats)},
        {"nonfinite_dropped", stats.nonFiniteDropped},
        {"interrupted", stats.interrupted},
        {"resumed", a.resume},
    };
    if (stats.firstNonFinite)
        j["first_nonfinite"] = {{"x", stats.firstNonFinite->x}, {"y", stats.firstNonFinite->y}, {"sample", stats.firstNonFinite->sample}};
    if (checkpoints.enabled() && stats.interrupted) j["checkpoint"] = checkpoints.path();
    std::cout << j.dump() << std::endl;
}

int runRender(const RenderArgs& a) {
    Scene scene = loadScene(a);

    RenderSettings s = resolveSettings(a, scene);
    checkFilmFits(a, s);
    // Checked before spending time on the render: the paths and the display transform.
    OutputPaths out = outputPaths(a);
    std::unique_ptr<Integrator> integrator = createIntegrator(s.integrator);
    AccelOptions accelOptions;
    accelOptions.threads = a.threads;
    std::unique_ptr<Accel> accel = createAccel(a.accel.empty() ? "embree" : a.accel, scene.geometry, accelOptions);
    Camera camera(*scene.camera, s.width, s.height);
    RenderContext ctx{scene, *accel, camera, s.maxDepth};
    if (!a.debugPixel.empty()) return runDebugPixel(a, ctx, *integrator, s);

    Film film(s.width, s.height);
    RenderOptions ro{.spp = s.spp, .timeLimitSeconds = a.timeLimit, .threads = a.threads, .seed = s.seed, .sampler = s.sampler};
    ro.stopAfterTiles = a.stopAfterTiles;
    Checkpoints checkpoints(a, out.exr, checkpointHeader(a, s, *scene.camera, *integrator, ro.tileSize));
    checkpoints.attach(a, film, ro);

    InterruptGuard guard;
    interruptFlag().store(false);
    ro.cancel = &interruptFlag();
    uint64_t total = a.timeLimit > 0 ? 0 : uint64_t(s.width) * uint64_t(s.height) * uint64_t(s.spp);
    total -= std::min(total, checkpoints.samplesResumed());
    ProgressReporter progress("render " + stem(a.scene), total, a.timeLimit, a.quiet);
    ro.progress = &progress;
    RenderStats stats = renderImage(ctx, *integrator, film, ro);

    io::Metadata md = imageMetadata(a.scene, s,
                                    ImageFacts{.integrator = std::string(integrator->name()), .accel = std::string(accel->name()),
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
    if (a.json) printJson(a, s, *integrator, *accel, stats, out, checkpoints);
    return stats.interrupted ? 130 : 0;
}

std::string joined(const std::vector<std::string>& v) {
    std::string s;
    for (const std::string& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
}

}  // namespace

void printError(const std::string& message) { std::cerr << "tessera: error: " << message << std::endl; }
void printWarning(const std::string& message) { std::cerr << "tessera: warning: " << message << std::endl; }

Runner addRenderCommand(CLI::App& app) {
    auto a = std::make_shared<RenderArgs>();
    CLI::App* cmd = app.add_subcommand("render", "Render a glTF 2.0 scene to EXR (and PNG)");
    cmd->add_option("SCENE", a->scene, "scene file (.gltf or .glb)")->required();
    cmd->add_option("-o,--output", a->output, "output EXR (default: out/<scene>.exr)");
    cmd->add_option("--png", a->png, "also write a display-referred PNG here (default: the EXR path with .png)");
    cmd->add_flag("--no-png", a->noPng, "write only the EXR");
    auto* spp = cmd->add_option("--spp", a->spp, "samples per pixel (default: the scene's, else 16)")->check(CLI::Range(1, 1 << 30));
    cmd->add_option("--time", a->timeLimit, "render progressive passes for this many seconds instead of a fixed spp")
        ->check(CLI::PositiveNumber)->excludes(spp);
    cmd->add_option("--threads", a->threads, "worker threads (default: all cores)")->check(CLI::Range(1, 4096));
    cmd->add_option("--seed", a->seed, "random seed (default: the scene's, else 0)")->check(CLI::NonNegativeNumber);
    addSamplerOption(*cmd, *a);
    cmd->add_option("--resolution", a->resolution, "image size WxH, e.g. 640x480 (default: the scene's)");
    cmd->add_option("--integrator", a->integrator, "light transport algorithm: " + joined(integratorNames()) + " (default: ptnee)");
    cmd->add_option("--accel", a->accel, "acceleration structure: " + joined(accelNames()) + " (default: embree)");
    cmd->add_option("--max-depth", a->maxDepth, "maximum number of bounces, -1 = unlimited (Russian roulette ends paths)")
        ->check(CLI::Range(-1, 1 << 20));
    cmd->add_option("--bdpt-strategies", a->bdptStrategies,
                    "also write one EXR per BDPT strategy (s,t), weighted and unweighted, into this directory "
                    "(paths up to --max-depth + 2 vertices, 5 if unlimited; one extra render per image)");
    cmd->add_option("--env", a->env,
                    "environment light: an equirectangular HDR image (EXR, .hdr; centre = +X horizon, top = +Y) or a "
                    "constant colour R,G,B; replaces the scene's TESSERA_environment");
    cmd->add_option("--env-rotate", a->envRotate, "turn the environment by DEG about +Y (counter-clockwise seen from above)");
    cmd->add_option("--env-intensity", a->envIntensity, "scale the environment's radiance")->check(CLI::NonNegativeNumber);
    cmd->add_option("--look-at", a->lookAt, "camera EX,EY,EZ,TX,TY,TZ[,UX,UY,UZ]: replaces the scene's camera");
    cmd->add_option("--fov", a->fovDeg, "vertical field of view in degrees (with or without --look-at)")->check(CLI::Range(0.001, 179.0));
    cmd->add_option("--display", a->display, "OCIO display for the PNG (default: sRGB)");
    cmd->add_option("--view", a->view, "OCIO view for the PNG: Standard, \"ACES 1.0 SDR-video\", Raw (default: Standard)");
    cmd->add_flag("--allow-external-files", a->allowExternalFiles,
                  "let the scene reference files outside its own folder (off: '..', absolute paths and symlinks out are refused)");
    cmd->add_option("--max-memory", a->maxMemoryGiB, "memory limit in GiB for input files and the film (default: 16)")
        ->check(CLI::Range(0.001, 1e6));
    cmd->add_option("--checkpoint", a->checkpointSeconds,
                    "write the accumulation state to OUT.ckpt (OUT: the EXR path) at the first pass boundary after every SEC "
                    "seconds and when interrupted; removed when the render completes")
        ->check(CLI::NonNegativeNumber);
    cmd->add_flag("--resume", a->resume,
                  "continue the render saved in OUT.ckpt (same scene and settings; refused with the setting that differs)");
    cmd->add_option("--debug-pixel", a->debugPixel,
                    "replay one camera sample x,y,s exactly as the render takes it, tracing its rays, hits, splats and the "
                    "first non-finite value on stderr; prints the radiance (or JSON with --json) and writes no image");
    cmd->add_option("--stop-after-tiles", a->stopAfterTiles, "test hook: behave as if interrupted after this many tiles")
        ->group("");
    cmd->add_flag("--quiet", a->quiet, "no progress output");
    cmd->add_flag("--json", a->json, "print one JSON object with the run's figures on stdout when done");
    cmd->footer("Ctrl-C stops at the next tile and still writes what was rendered (exit code 130); press it\n"
                "twice to quit at once. Outputs are written to a temporary file and renamed, never half-written.");
    return [a] { return runRender(*a); };
}

}  // namespace tessera::app
