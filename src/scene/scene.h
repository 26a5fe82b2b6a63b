#pragma once
/// \file scene.h
/// A loaded scene: geometry, materials, lights, camera and the render defaults the file asks for.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/sampler_kind.h"
#include "geometry/hit.h"
#include "geometry/shapes.h"
#include "materials/material.h"
#include "scene/camera.h"
#include "scene/lights.h"

namespace tessera {

/// Render defaults a scene may carry (glTF extension TESSERA_render); the command line overrides them.
struct RenderSettings {
    int width = 512;
    int height = 512;
    int spp = 16;
    int maxDepth = -1;  ///< maximum number of bounces; −1 = unlimited (Russian roulette ends paths)
    uint64_t seed = 0;
    SamplerKind sampler = kDefaultSampler;  ///< --sampler (core/sampler.h)
    std::string integrator = "ptnee";
    // Photon mapping (`sppm`, `vcm`; integrators/photon_pass.h): initial radius in scene units
    // (< 0: chosen from the scene's size and the photon count; 0: no merging), Knaus & Zwicker's α,
    // light sub-paths per iteration (0: one per pixel).
    float photonRadius = -1.f;
    float photonAlpha = 0.75f;
    uint64_t photonPaths = 0;
};

/// The local geometry at a ray hit, in world space.
struct SurfaceInteraction {
    Vec3f p{0.f};
    Vec3f ng{0.f};  ///< unit geometric normal (triangle winding / sphere outward)
    Vec3f ns{0.f};  ///< unit shading normal, in the same hemisphere as ng
    uint32_t materialId = 0;
    uint32_t lightIndex = kInvalidId;
    uint32_t geomId = kInvalidId;  ///< the primitive hit (SceneGeometry numbering, as in Hit)
    uint32_t instId = kInvalidId;  ///< the instance hit (SceneGeometry::instances), or kInvalidId
    uint32_t primId = kInvalidId;
    Vec2f bary{0.f};               ///< the hit's (u, v): barycentrics of vertices 1 and 2 (triangles)
};

/// A camera the scene file places (glTF: a node with a camera), for picking one by name or index.
struct SceneCamera {
    int index = -1;        ///< its index in the file's cameras[]
    std::string name;      ///< the camera's name
    std::string nodeName;  ///< the name of the node that places it
    std::optional<CameraDesc> desc;  ///< empty: not renderable, `problem` says why
    std::string problem;
};

class Scene {
public:
    Scene() = default;
    /// Moving a scene re-binds its light set to the moved geometry (the lights point into it).
    Scene(Scene&& other) noexcept;
    Scene& operator=(Scene&& other) noexcept;
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    SceneGeometry geometry;
    std::vector<Material> materials;
    std::vector<std::unique_ptr<Image>> images;  ///< decoded textures; materials and alpha masks point into them
    std::vector<PointLightDesc> pointLights;  ///< KHR_lights_punctual point lights (world space)
    std::vector<SpotLightDesc> spotLights;    ///< KHR_lights_punctual spot lights (world space)
    std::vector<DirectionalLightDesc> directionalLights;  ///< KHR_lights_punctual directional lights
    std::optional<EnvironmentDesc> environment;           ///< TESSERA_environment or --env
    std::optional<CameraDesc> camera;   ///< the camera a render uses: the file's first (or the command line's)
    std::vector<SceneCamera> cameras;   ///< every camera the file places, in traversal order
    RenderSettings settings;
    std::string sourcePath;  ///< the file it was loaded from (for messages and metadata)

    /// Builds the light set; call after geometry and materials are final (again after changing lights).
    void finalize();
    const LightSet& lights() const { return lights_; }
    /// True when some material is an absorbing volume (KHR_materials_volume with a finite
    /// attenuation distance, integrators/volume.h): without one no segment is ever attenuated, and
    /// the bidirectional connections skip the per-segment test. Set by finalize().
    bool hasVolumes() const { return hasVolumes_; }

    /// Fills the surface interaction of `hit` for `ray`. The point is recomputed from the primitive
    /// (barycentric interpolation / reprojection onto the sphere), which is far more accurate than
    /// o + t·d and is what makes ray spawning with a few ulps of offset safe.
    SurfaceInteraction interaction(const Ray& ray, const Hit& hit) const;
    /// The BSDF inputs at `si`: its material's factors times its textures there. `footprintW` is the
    /// world-space width of the ray footprint at si.p (Camera::pixelFootprint; 0: finest MIP level);
    /// it is turned into uv units with the triangle's uv density for each texture's TEXCOORD set.
    BsdfParams bsdfParams(const SurfaceInteraction& si, float footprintW = 0.f) const;

private:
    LightSet lights_;
    bool hasVolumes_ = false;
};

}  // namespace tessera
