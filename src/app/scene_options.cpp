/// \file scene_options.cpp
#include "app/scene_options.h"

#include <glm/gtc/matrix_transform.hpp>

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "app/commands.h"
#include "core/error.h"
#include "core/fnv1a.h"
#include "core/version.h"
#include "render/film.h"
#include "scene/gltf_loader.h"

namespace tessera::app {

std::vector<float> parseNumbers(const std::string& text, const std::string& option) {
    std::vector<float> v;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        try {
            size_t used = 0;
            v.push_back(std::stof(item, &used));
            if (used != item.size()) throw std::invalid_argument(item);
        } catch (const std::exception&) {
            throw InputError(option + ": '" + item + "' is not a number");
        }
    }
    return v;
}

std::string stem(const std::string& path) { return std::filesystem::path(path).stem().string(); }

namespace {

/// --look-at EX,EY,EZ,TX,TY,TZ[,UX,UY,UZ] → a camera-to-world matrix looking down local −z.
Mat4f lookAtCamera(const std::string& text) {
    std::vector<float> v = parseNumbers(text, "--look-at");
    if (v.size() != 6 && v.size() != 9) throw InputError("--look-at needs 6 or 9 comma-separated numbers");
    Vec3f eye(v[0], v[1], v[2]), target(v[3], v[4], v[5]);
    Vec3f up = v.size() == 9 ? Vec3f(v[6], v[7], v[8]) : Vec3f(0, 1, 0);
    Vec3f f = target - eye;
    if (!(glm::length(f) > 0.f) || !(glm::length(glm::cross(f, up)) > 0.f))
        throw InputError("--look-at: eye and target coincide or the up vector is parallel to the view direction");
    return glm::inverse(glm::lookAt(eye, target, up));
}

/// "640x480" → (width, height), each side 1..65536.
void parseResolution(const std::string& text, int& width, int& height) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    std::stringstream ss(text);
    if (!(ss >> w >> x >> h) || (x != 'x' && x != 'X') || (ss >> extra) || w < 1 || h < 1 || w > 65536 || h > 65536)
        throw InputError("--resolution must look like 640x480 (each side 1..65536), got '" + text + "'");
    width = w;
    height = h;
}

}  // namespace

/// `--env FILE|R,G,B [--env-rotate DEG] [--env-intensity S]`: replaces (or adjusts) the scene's
/// environment light and rebuilds its light set. Rotation and intensity given alone adjust the
/// scene's own environment.
void applyEnvironmentOptions(const SceneOptions& a, Scene& scene) {
    if (a.env.empty() && !a.envRotate && !a.envIntensity) return;
    if (!a.env.empty()) {
        EnvironmentDesc env;
        bool isColor = a.env.find(',') != std::string::npos && !std::filesystem::exists(a.env);
        if (isColor) {
            std::vector<float> c = parseNumbers(a.env, "--env");
            if (c.size() != 3 || !(c[0] >= 0.f && c[1] >= 0.f && c[2] >= 0.f) || !isFinite(Vec3f(c[0], c[1], c[2])))
                throw InputError("--env: a colour must be three finite non-negative numbers R,G,B, got '" + a.env + "'");
            env.color = Rgb(c[0], c[1], c[2]);
            env.source = "constant " + a.env;
        } else {
            scene.images.push_back(readEnvironmentImage(a.env));
            env.image = scene.images.back().get();
            env.source = a.env;
        }
        scene.environment = env;
    }
    if (!scene.environment)
        throw InputError("--env-rotate and --env-intensity need an environment: the scene has none, add --env FILE|R,G,B");
    if (a.envRotate) scene.environment->rotationDeg = float(*a.envRotate);
    if (a.envIntensity) scene.environment->intensity = float(*a.envIntensity);
    scene.finalize();
}

Scene loadScene(const SceneOptions& a) {
    std::vector<std::string> warnings;
    SceneLoadOptions loadOptions;
    loadOptions.allowExternalFiles = a.allowExternalFiles;
    loadOptions.maxFileBytes = uint64_t(a.maxMemoryGiB * double(1ull << 30));
    Scene scene = loadGltfScene(a.scene, warnings, loadOptions);
    for (const std::string& w : warnings) printWarning(w);
    return scene;
}

void addSamplerOption(CLI::App& cmd, SceneOptions& o) {
    cmd.add_option("--sampler", o.sampler,
                   "random numbers: sobol (Owen-scrambled Sobol', default) or independent (PCG32 per sample)");
}

RenderSettings resolveRenderSettings(const SceneOptions& a, const Scene& scene) {
    RenderSettings s = scene.settings;
    if (!a.resolution.empty()) parseResolution(a.resolution, s.width, s.height);
    if (a.spp > 0) s.spp = a.spp;
    if (a.maxDepth) s.maxDepth = *a.maxDepth;
    if (a.seed >= 0) s.seed = uint64_t(a.seed);
    if (!a.sampler.empty()) {
        std::optional<SamplerKind> kind = parseSamplerKind(a.sampler);
        if (!kind) throw InputError("--sampler: unknown sampler '" + a.sampler + "' (sobol, independent)");
        s.sampler = *kind;
    }
    if (!a.integrator.empty()) s.integrator = a.integrator;
    if (a.photonRadius) s.photonRadius = *a.photonRadius;
    if (a.photonAlpha) s.photonAlpha = *a.photonAlpha;
    if (a.photonPaths) s.photonPaths = *a.photonPaths;
    return s;
}

CameraDesc resolveCamera(const SceneOptions& a, const std::optional<CameraDesc>& base) {
    std::optional<CameraDesc> camera = base;
    if (!a.lookAt.empty()) {
        CameraDesc d = camera.value_or(CameraDesc{});
        d.cameraToWorld = lookAtCamera(a.lookAt);
        camera = d;
    }
    if (a.fovDeg > 0.0) {
        if (!camera) throw InputError("--fov needs a camera: the scene has none, add --look-at");
        camera->yfov = float(a.fovDeg * kPi / 180.0);
    }
    if (!camera)
        throw SceneError(a.scene, "cameras", "the scene has no camera; give one with --look-at EX,EY,EZ,TX,TY,TZ [--fov DEG]");
    return *camera;
}

RenderSettings resolveSettings(const SceneOptions& a, Scene& scene) {
    applyEnvironmentOptions(a, scene);
    RenderSettings s = resolveRenderSettings(a, scene);
    scene.camera = resolveCamera(a, scene.camera);
    return s;
}

void checkFilmFits(const SceneOptions& a, const RenderSettings& s) {
    double filmBytes = Film::memoryBytes(s.width, s.height);
    if (filmBytes > a.maxMemoryGiB * double(1ull << 30))
        throw InputError(a.scene + ": " + (a.resolution.empty() ? "extensions.TESSERA_render: " : "--resolution: ") +
                         "resolution " + std::to_string(s.width) + "x" + std::to_string(s.height) + " needs " +
                         std::to_string(int(filmBytes / double(1ull << 30) + 0.5)) + " GiB of film memory, over the limit of " +
                         std::to_string(int(a.maxMemoryGiB)) + " GiB (--max-memory)");
}

io::Metadata imageMetadata(const std::string& scenePath, const RenderSettings& s, const ImageFacts& f) {
    io::Metadata md = {
        {"Software", std::string("Tessera ") + versionString() + " (" + gitRevision() + ")"},
        {"tessera:version", versionString()},
        {"tessera:git", gitRevision()},
        {"tessera:scene", scenePath},
        {"tessera:scene_hash", fnv1a64OfFile(scenePath)},
        {"tessera:integrator", f.integrator},
        {"tessera:accel", f.accel},
        {"tessera:spp", std::to_string(f.spp)},
        {"tessera:samples", std::to_string(f.samples)},
        {"tessera:seed", std::to_string(s.seed)},
        {"tessera:sampler", std::string(samplerName(s.sampler))},
        {"tessera:max_depth", std::to_string(s.maxDepth)},
        {"tessera:resolution", std::to_string(s.width) + "x" + std::to_string(s.height)},
        {"tessera:render_seconds", std::to_string(f.seconds)},
        {"tessera:threads", std::to_string(f.threads)},
        {"tessera:nonfinite_dropped", std::to_string(f.nonFiniteDropped)},
        {"tessera:interrupted", f.interrupted ? "true" : "false"},
        {"tessera:resumed", f.resumed ? "true" : "false"},
    };
    for (const auto& [key, value] : photonSettings(s)) md.push_back({"tessera:" + key, value});
    return md;
}

std::string exactFloat(float v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%a", double(v));
    return buf;
}

std::vector<std::pair<std::string, std::string>> photonSettings(const RenderSettings& s) {
    if (s.integrator != "sppm" && s.integrator != "vcm") return {};
    return {{"photon_radius", exactFloat(s.photonRadius)}, {"photon_alpha", exactFloat(s.photonAlpha)},
            {"photon_paths", std::to_string(s.photonPaths)}};
}

}  // namespace tessera::app
