#pragma once
/// \file gltf_asset.h
/// Scene-level import of asset files that are never committed (scene/assets.h): the name lookup
/// that TESSERA_asset_mesh and TESSERA_asset_gltf share, and the merge of a glTF asset loaded as its
/// own Scene into the scene that names it (TESSERA_asset_gltf).
///
/// TESSERA_asset_gltf (node): {"asset": "webxr-input-profiles/hp-mixed-reality/left.glb"} places
/// the asset's default scene (its meshes, materials, textures, lights and node hierarchy) under the
/// node's transform. The asset is read by the same loader with the same limits; its own URIs are
/// confined to its own folder; its cameras and TESSERA_render settings are not used.
#include <string>
#include <vector>

#include "scene/scene.h"

namespace tessera {

struct SceneLoadOptions;

/// The path of asset `name` in `roots`, or a SceneError naming `sceneFile`, `element` and the
/// problem: an invalid name (absolute, '..', odd characters), an asset in no asset folder (with the
/// folders searched and how to fetch it), or a file that would take `bytesSoFar` (the asset bytes
/// the scene has read so far, which the file's size is added to) over `maxBytes`. Every reference
/// counts, so a small scene naming a large asset ten thousand times is refused like a large file.
std::string resolveAssetOrThrow(const std::string& name, const std::vector<std::string>& roots, uint64_t maxBytes,
                                uint64_t& bytesSoFar, const std::string& sceneFile, const std::string& element);

/// Appends `asset` (already placed in `into`'s world space) to `into`: its materials after
/// `into`'s (every mesh's and sphere's materialId offset by the count before), its images (moved:
/// the materials' and alpha masks' image pointers stay valid), meshes, spheres and point lights.
/// `into` is not finalized here.
void appendAssetScene(Scene& into, Scene&& asset);

}  // namespace tessera
