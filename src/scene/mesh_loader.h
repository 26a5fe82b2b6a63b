#pragma once
/// \file mesh_loader.h
/// Loads bare triangle meshes for the acceleration-structure tools: PLY (ASCII, binary little and
/// big endian; gzip-compressed too) and Wavefront OBJ (positions and faces only). Polygons are
/// triangulated as fans. glTF scenes name such meshes too (TESSERA_asset_mesh); scene/scene_loader.h
/// is the front door that takes any of these files or a glTF scene.
#include <string>
#include <vector>

#include "geometry/shapes.h"

namespace tessera {

struct MeshLoadOptions {
    /// Refuse files (after gzip decompression) and declared element counts whose data would need
    /// more memory than this, before allocating it (allocation bombs).
    uint64_t maxBytes = uint64_t(16) << 30;
};

/// Reads a PLY file (optionally .gz): the `vertex` element's x, y, z and the `face` element's vertex
/// index list. Throws SceneError "FILE: element NAME, row R: PROBLEM" (rows counted from 0, like
/// PLY's vertex indices) or "FILE: header line L: PROBLEM" on malformed input: truncated data, bad
/// header, counts over the memory limit or the file's size, non-finite coordinates, indices out
/// of range, a corrupt gzip stream.
TriangleMesh loadPlyMesh(const std::string& path, const MeshLoadOptions& options = {});

/// Reads `v` and `f` records of an OBJ file (negative indices allowed; texture/normal indices ignored).
/// Throws SceneError "FILE: line L: PROBLEM" on a malformed record, a non-finite coordinate or an
/// index out of range.
TriangleMesh loadObjMesh(const std::string& path, const MeshLoadOptions& options = {});

}  // namespace tessera
