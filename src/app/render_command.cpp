/// \file render_command.cpp
/// `tessera render SCENE`: load, build the acceleration structure, render, write EXR + PNG.
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>

#include "accel/accel.h"
#include "app/commands.h"
#include "app/render_job.h"
#include "app/scene_options.h"
#include "core/error.h"
#include "integrators/integrator.h"
#include "render/debug_pixel.h"
#include "render/interrupt.h"
#include "render/renderer.h"

namespace tessera::app {
namespace {

/// `tessera render`'s command line: one render job, plus the options that are not a render.
struct RenderArgs : RenderJob {
    std::string debugPixel;  ///< "x,y,s": replay one sample with a trace instead of rendering
    bool json = false;
};

/// "x,y,s" → the sample to replay; checked against the image size.
SampleId parseDebugPixel(const std::string& text, int width, int height) {
    std::vector<float> v = parseNumbers(text, "--debug-pixel");
    if (v.size() != 3 || v[0] != std::floor(v[0]) || v[1] != std::floor(v[1]) || v[2] != std::floor(v[2]) || v[0] < 0 ||
        v[1] < 0 || v[2] < 0 || v[0] >= float(width) || v[1] >= float(height) || v[2] > 4e9f)
        throw InputError("--debug-pixel needs x,y,s: a pixel inside the " + std::to_string(width) + "x" + std::to_string(height) +
                         " image and a sample index >= 0, got '" + text + "'");
    return SampleId{int(v[0]), int(v[1]), uint32_t(v[2])};
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

/// `--json`: the run's figures as one JSON object on stdout.
void printJson(const RenderArgs& a, const RenderSettings& s, const Accel& accel, const RenderJobResult& r, const JobPlan& plan) {
    const RenderStats& stats = r.stats;
    const OutputPaths& out = plan.out;
    nlohmann::json j = {
        {"scene", a.scene},
        {"integrator", std::string(plan.integrator->name())},
        {"accel", std::string(accel.name())},
        {"spp", stats.sppCompleted},
        {"samples", stats.samples},
        {"seconds", stats.seconds},
        {"build_seconds", accel.stats().buildSeconds},
        {"resolution", {s.width, s.height}},
        {"threads", stats.threads},
        {"seed", s.seed},
        {"sampler", samplerName(s.sampler)},
        {"outputs", !a.samples.empty() ? nlohmann::json{{"partial", out.exr}}
                    : out.png.empty()  ? nlohmann::json{{"exr", out.exr}}
                                       : nlohmann::json{{"exr", out.exr}, {"png", out.png}}},
        {"samples_per_second", samplesPerSecond(stats)},
        {"nonfinite_dropped", stats.nonFiniteDropped},
        {"interrupted", stats.interrupted},
        {"resumed", a.resume},
    };
    if (stats.firstNonFinite)
        j["first_nonfinite"] = {{"x", stats.firstNonFinite->x}, {"y", stats.firstNonFinite->y}, {"sample", stats.firstNonFinite->sample}};
    if (!r.checkpoint.empty()) j["checkpoint"] = r.checkpoint;
    std::cout << j.dump() << std::endl;
}

int runRender(const RenderArgs& a) {
    Scene scene = loadScene(a);

    RenderSettings s = resolveSettings(a, scene);
    // Checked before spending time on the render: film memory, the paths, the display transform, the integrator.
    JobPlan plan = planRenderJob(a, s, *scene.camera);
    AccelOptions accelOptions;
    accelOptions.threads = a.threads;
    std::unique_ptr<Accel> accel = createAccel(accelName(a), scene.geometry, accelOptions);
    if (!a.debugPixel.empty()) {
        Camera camera(plan.camera, s.width, s.height);
        return runDebugPixel(a, RenderContext{scene, *accel, camera, s.maxDepth}, *plan.integrator, s);
    }

    interruptFlag().store(false);
    RenderJobResult r = runRenderJob(a, plan, scene, *accel, "render " + stem(a.scene));
    if (a.json) printJson(a, s, *accel, r, plan);
    return r.stats.interrupted ? 130 : 0;
}

}  // namespace

std::string commaSeparated(const std::vector<std::string>& names) {
    std::string s;
    for (const std::string& x : names) s += (s.empty() ? "" : ", ") + x;
    return s;
}

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
    cmd->add_option("--integrator", a->integrator, "light transport algorithm: " + commaSeparated(integratorNames()) + " (default: ptnee)");
    cmd->add_option("--accel", a->accel, "acceleration structure: " + commaSeparated(accelNames()) + " (default: embree)");
    cmd->add_option("--max-depth", a->maxDepth, "maximum number of bounces, -1 = unlimited (Russian roulette ends paths)")
        ->check(CLI::Range(-1, 1 << 20));
    cmd->add_option("--bdpt-strategies", a->bdptStrategies,
                    "also write one EXR per BDPT strategy (s,t), weighted and unweighted, into this directory "
                    "(paths up to --max-depth + 2 vertices, 5 if unlimited; one extra render per image)");
    cmd->add_option("--radius", a->photonRadius, "sppm, vcm: initial merge radius in scene units (default: 0.003 x the scene's radius, "
                    "grown as 1/sqrt(photons) below 512^2 photons, at most a pixel's footprint at the median depth seen; "
                    "vcm: 0 = no merging, i.e. bdpt)")->check(CLI::NonNegativeNumber);
    cmd->add_option("--alpha", a->photonAlpha, "sppm, vcm: radius reduction, r_{i+1}^2 = r_i^2 (i + alpha)/(i + 1) (default: 0.75)")
        ->check(CLI::Range(0.01, 0.999));
    cmd->add_option("--photons", a->photonPaths, "sppm, vcm: light sub-paths per iteration (default: one per pixel)")->check(CLI::Range(uint64_t(1), uint64_t(1) << 32));
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
    cmd->add_option("--samples", a->samples,
                    "render only sample indices A:B (A inclusive, B exclusive, B <= --spp) of every pixel into a partial "
                    "(-o, default out/<scene>_A-B.partial); 'tessera merge' joins partials into the image");
    cmd->add_option("--stop-after-tiles", a->stopAfterTiles, "test hook: behave as if interrupted after this many tiles")
        ->group("");
    cmd->add_flag("--quiet", a->quiet, "no progress output");
    cmd->add_flag("--json", a->json, "print one JSON object with the run's figures on stdout when done");
    cmd->footer("Ctrl-C stops at the next tile and still writes what was rendered (exit code 130); press it\n"
                "twice to quit at once. Outputs are written to a temporary file and renamed, never half-written.");
    return [a] { return runRender(*a); };
}

}  // namespace tessera::app
