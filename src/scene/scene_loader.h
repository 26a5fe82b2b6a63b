#pragma once
/// \file scene_loader.h
/// The front door for the acceleration-structure tools and the library: any scene or mesh file,
/// dispatched by its extension to the glTF loader (scene/gltf_loader.h) or the PLY/OBJ readers
/// (scene/mesh_loader.h). Includes point one way: this file uses both loaders, the glTF loader uses
/// the mesh readers for its asset meshes, the mesh readers use neither.
#include <optional>
#include <string>
#include <vector>

#include "scene/mesh_loader.h"
#include "scene/scene.h"

namespace tessera {

/// Geometry of a glTF scene (.gltf/.glb, with its camera when it has one), PLY (.ply, .ply.gz) or
/// OBJ file, chosen by extension. Non-fatal problems go to `warnings`. Throws InputError for any
/// other extension. `instanceMeshes`: SceneLoadOptions::instanceMeshes for glTF scenes.
SceneGeometry loadGeometryFile(const std::string& path, std::optional<CameraDesc>& camera,
                               std::vector<std::string>& warnings, const MeshLoadOptions& options = {}, bool instanceMeshes = true);

}  // namespace tessera
