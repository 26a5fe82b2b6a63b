#pragma once
/// \file scene_options.h
/// What `tessera render` and `tessera view` share: the options that pick and override a scene
/// (resolution, integrator, seed, camera, environment, limits), loading it with its warnings, the
/// resolved render settings, and the metadata an output image records. One home, so that a view's
/// saved image and a batch render of the same camera say the same things.
#include <optional>
#include <string>
#include <vector>

#include "io/image_output.h"
#include "scene/scene.h"

namespace CLI {
class App;
}

namespace tessera::app {

/// The scene options of both commands (each registers them on its own command line).
struct SceneOptions {
    std::string scene, resolution, integrator, lookAt;
    std::string env;  ///< --env FILE|R,G,B: replaces the scene's environment
    std::optional<double> envRotate, envIntensity;
    int spp = 0;                   ///< 0: the scene's
    std::optional<int> maxDepth;   ///< --max-depth; unset: the scene's
    int64_t seed = -1;             ///< < 0: the scene's
    std::string sampler;           ///< --sampler sobol|independent; empty: sobol
    double fovDeg = 0.0;           ///< 0: the camera's
    bool allowExternalFiles = false;
    double maxMemoryGiB = 16.0;    ///< input files and the film
    std::optional<float> photonRadius, photonAlpha;  ///< --radius, --alpha (sppm, vcm)
    std::optional<uint64_t> photonPaths;             ///< --photons (sppm, vcm)
};

/// Registers `--sampler` (render and view).
void addSamplerOption(CLI::App& cmd, SceneOptions& o);

/// "a,b,c" → numbers; InputError naming `option` on anything else.
std::vector<float> parseNumbers(const std::string& text, const std::string& option);
/// The file name without folder and extension ("scenes/box.gltf" → "box").
std::string stem(const std::string& path);

/// Loads `o.scene` under the options' limits and prints its warnings.
Scene loadScene(const SceneOptions& o);
/// The scene's render settings with the command line's overrides. The camera and environment
/// options change `scene`; a scene without a camera needs --look-at.
RenderSettings resolveSettings(const SceneOptions& o, Scene& scene);

/// The parts of resolveSettings, for renders that share one loaded scene (`tessera batch`):
/// the environment options (they change the scene's lights, so they belong to the loaded scene);
void applyEnvironmentOptions(const SceneOptions& o, Scene& scene);
/// the resolution, spp, depth, seed and integrator overrides of the scene's settings;
RenderSettings resolveRenderSettings(const SceneOptions& o, const Scene& scene);
/// `base` (the scene's camera, or one picked from Scene::cameras) with the --look-at and --fov
/// overrides; SceneError naming `o.scene` when there is no camera at all.
CameraDesc resolveCamera(const SceneOptions& o, const std::optional<CameraDesc>& base);
/// Refuses a resolution whose film alone would exceed the memory limit, instead of dying in the
/// allocator.
void checkFilmFits(const SceneOptions& o, const RenderSettings& s);

/// Hexadecimal float: the exact bits, so a setting changed in the last digit is a different setting.
std::string exactFloat(float v);

/// The settings that change an `sppm` or `vcm` image (empty for other integrators): what its metadata and
/// its checkpoint and partial-file headers record, so that resumes and merges refuse a mismatch.
std::vector<std::pair<std::string, std::string>> photonSettings(const RenderSettings& s);

/// What an output image's metadata says about the samples it holds.
struct ImageFacts {
    std::string integrator, accel;
    uint64_t spp = 0, samples = 0, nonFiniteDropped = 0;
    double seconds = 0.0;
    int threads = 0;
    bool interrupted = false, resumed = false;
};
/// The provenance every output image records (EXR attributes, PNG text).
io::Metadata imageMetadata(const std::string& scenePath, const RenderSettings& s, const ImageFacts& f);

}  // namespace tessera::app
