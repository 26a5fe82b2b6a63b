#include "scene/scene_loader.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "core/error.h"
#include "scene/gltf_loader.h"

namespace tessera {
namespace {

/// The extension in lower case, a trailing ".gz" looked through (".ply.gz" → ".ply").
std::string lowerExtension(const std::string& path) {
    std::string p = path;
    std::transform(p.begin(), p.end(), p.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (p.size() > 3 && p.ends_with(".gz")) p.resize(p.size() - 3);
    return std::filesystem::path(p).extension().string();
}

}  // namespace

SceneGeometry loadGeometryFile(const std::string& path, std::optional<CameraDesc>& camera,
                               std::vector<std::string>& warnings, const MeshLoadOptions& options, bool instanceMeshes) {
    std::string ext = lowerExtension(path);
    SceneGeometry g;
    if (ext == ".gltf" || ext == ".glb") {
        SceneLoadOptions sceneOptions;
        sceneOptions.instanceMeshes = instanceMeshes;
        Scene scene = loadGltfScene(path, warnings, sceneOptions);
        camera = scene.camera;
        g.meshes = std::move(scene.geometry.meshes);
        g.spheres = std::move(scene.geometry.spheres);
        g.prototypes = std::move(scene.geometry.prototypes);
        g.instances = std::move(scene.geometry.instances);
        // Alpha masks point into the scene's images: they move along (same addresses) and live as
        // long as the geometry.
        g.maskImages = std::make_shared<const std::vector<std::unique_ptr<Image>>>(std::move(scene.images));
    } else if (ext == ".ply") {
        g.meshes.push_back(loadPlyMesh(path, options));
    } else if (ext == ".obj") {
        g.meshes.push_back(loadObjMesh(path, options));
    } else {
        throw InputError(path + ": unknown file type (expected .gltf, .glb, .ply, .ply.gz or .obj)");
    }
    return g;
}

}  // namespace tessera
