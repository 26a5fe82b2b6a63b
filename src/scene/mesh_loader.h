#pragma once
/// \file mesh_loader.h
/// Loads bare triangle meshes for the acceleration-structure tools: PLY (ASCII, binary little and
/// big endian; gzip-compressed too) and Wavefront OBJ (positions and faces only). Polygons are
/// triangulated as fans. Also a front door that takes any of these or a glTF scene.
#include <optional>
#include <string>
#include <vector>

#include "geometry/shapes.h"
#include "scene/camera.h"

namespace tessera {

/// Reads a PLY file (optionally .gz): the `vertex` element's x, y, z and the `face` element's vertex
/// index list. Throws SceneError on malformed input or out-of-range indices.
TriangleMesh loadPlyMesh(const std::string& path);

/// Reads `v` and `f` records of an OBJ file (negative indices allowed; texture/normal indices ignored).
TriangleMesh loadObjMesh(const std::string& path);

/// Geometry of a glTF scene (.gltf/.glb, with its camera when it has one), PLY or OBJ file, chosen by
/// extension. Non-fatal problems go to `warnings`.
SceneGeometry loadGeometryFile(const std::string& path, std::optional<CameraDesc>& camera,
                               std::vector<std::string>& warnings);

}  // namespace tessera
