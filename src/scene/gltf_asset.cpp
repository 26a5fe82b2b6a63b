#include "scene/gltf_asset.h"

#include <filesystem>

#include "core/error.h"
#include "scene/assets.h"

namespace tessera {

std::string resolveAssetOrThrow(const std::string& name, const std::vector<std::string>& roots, uint64_t maxBytes,
                                uint64_t& bytesSoFar, const std::string& sceneFile, const std::string& element) {
    if (!isValidAssetName(name))
        throw SceneError(sceneFile, element,
                         "asset name '" + name + "' must be a relative path of [A-Za-z0-9._-] components without '..'");
    std::optional<std::string> file = resolveAsset(name, roots);
    if (!file) {
        std::string list;
        for (const std::string& r : roots) list += (list.empty() ? "" : ", ") + r;
        throw SceneError(sceneFile, element,
                         "asset '" + name + "' not found in the asset folders (" + (list.empty() ? "none" : list) +
                             "); run tools/fetch_assets.sh or set TESSERA_ASSETS");
    }
    std::error_code ec;
    uint64_t size = std::filesystem::file_size(*file, ec);
    if (ec) throw SceneError(sceneFile, element, "asset '" + *file + "' is unreadable");
    if (size > maxBytes || bytesSoFar > maxBytes - size)
        throw SceneError(sceneFile, element,
                         "asset '" + name + "' (" + std::to_string(size) + " bytes) takes the scene's assets to " +
                             std::to_string(bytesSoFar + size) + " bytes, over the limit of " + std::to_string(maxBytes));
    bytesSoFar += size;
    return *file;
}

void appendAssetScene(Scene& into, Scene&& asset) {
    // Material ids are indices into Scene::materials: the asset's shift by the materials already there.
    // Images are owned through unique_ptr, so moving them keeps every TextureRef's pointer valid.
    const auto base = uint32_t(into.materials.size());
    for (Material& m : asset.materials) into.materials.push_back(std::move(m));
    for (std::unique_ptr<Image>& image : asset.images) into.images.push_back(std::move(image));
    for (TriangleMesh& mesh : asset.geometry.meshes) {
        mesh.materialId += base;
        into.geometry.meshes.push_back(std::move(mesh));
    }
    const auto prototypeBase = uint32_t(into.geometry.prototypes.size());
    for (SceneGeometry& proto : asset.geometry.prototypes) {
        for (TriangleMesh& mesh : proto.meshes) mesh.materialId += base;
        into.geometry.prototypes.push_back(std::move(proto));
    }
    for (MeshInstance inst : asset.geometry.instances) {
        inst.prototype += prototypeBase;
        into.geometry.instances.push_back(inst);
    }
    for (Sphere& sphere : asset.geometry.spheres) {
        sphere.materialId += base;
        into.geometry.spheres.push_back(std::move(sphere));
    }
    for (const PointLightDesc& light : asset.pointLights) into.pointLights.push_back(light);
    for (const SpotLightDesc& light : asset.spotLights) into.spotLights.push_back(light);
    for (const DirectionalLightDesc& light : asset.directionalLights) into.directionalLights.push_back(light);
}

}  // namespace tessera
