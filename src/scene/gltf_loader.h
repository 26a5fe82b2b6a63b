#pragma once
/// \file gltf_loader.h
/// Loads glTF 2.0 scenes (.gltf, .glb) with tinygltf, plus Tessera's extensions:
///   TESSERA_render (root): render defaults {resolution [w,h], spp, maxDepth, seed, integrator}
///   TESSERA_sphere (node): analytic sphere {radius, material} centred at the node's origin
///   TESSERA_thin_lens (camera): {apertureRadius, focusDistance}
///   TESSERA_asset_mesh (node): {asset, material}: a PLY (.gz too) or OBJ mesh that is not committed,
///     named relative to the asset folders (scene/assets.h), placed by the node's transform
///   TESSERA_asset_gltf (node): {asset}: a glTF/GLB file from the asset folders (its meshes, materials,
///     textures, lights and node hierarchy) placed under the node's transform (scene/gltf_asset.h)
///   TESSERA_environment (root): {color [r,g,b], intensity, rotation (degrees about +Y), and "image"
///     (a file beside the scene) or "asset" (in the asset folders)}: the environment light
///     (scene/environment.h gives the equirectangular orientation)
/// KHR_mesh_quantization: integer POSITION/NORMAL components (normalized or not) are read as floats.
/// An extension the file requires but Tessera lacks is an error; one it only uses gives one warning
/// line saying what is ignored (as do vertex colours, morph targets, skins and animations).
/// Materials: every glTF factor goes into BsdfParams (finalizeBsdfParams picks the BSDF);
/// emissiveFactor × KHR_materials_emissive_strength makes every surface of the material a light.
/// Textures (scene/gltf_textures.h): baseColor, metallicRoughness, normal, emissive, and the
/// transmission/specular/specularColor textures of their extensions, with samplers,
/// KHR_texture_transform, TEXCOORD_0/_1; images are decoded once by decodeImage (GLB buffer views,
/// data URIs, files in the scene's folder), colour slots as sRGB. occlusionTexture is ignored (a
/// path tracer computes occlusion). alphaMode MASK (and BLEND, as MASK at 0.5 with a warning) gives
/// the meshes a shared AlphaMask. A normal texture without TANGENT gets MikkTSpace tangents
/// (scene/tangents.h).
/// Errors throw SceneError naming the file, the element (e.g. "meshes[3].primitives[0]") and the problem.
#include <string>
#include <vector>

#include "scene/assets.h"
#include "scene/scene.h"

namespace tessera {

/// Limits that keep a file from a stranger from reaching outside its folder or exhausting memory.
struct SceneLoadOptions {
    /// Allow buffer/image URIs that resolve outside the scene's folder (`..`, absolute paths,
    /// symlinks pointing out). Off by default: a scene file must not read arbitrary files.
    bool allowExternalFiles = false;
    /// Largest file (scene, buffer or image) read, in bytes. data: URIs are bounded by the scene
    /// file's size. The asset files a scene names (TESSERA_asset_mesh, TESSERA_asset_gltf) count
    /// together, every reference again. Also the most that the decoded images of one file together
    /// may take (--max-memory sets it).
    uint64_t maxFileBytes = uint64_t(4) << 30;
    /// Folders where TESSERA_asset_mesh and TESSERA_asset_gltf names are looked up (never the scene's
    /// own URIs).
    std::vector<std::string> assetRoots = defaultAssetRoots();
    /// A glTF mesh named by several nodes (or a TESSERA_asset_mesh asset named by several) is stored
    /// once, in object space, as a prototype that each node places as an instance
    /// (SceneGeometry::instances); emissive primitives stay flat. False: a world-space copy per
    /// node (`--no-instancing`), what the benchmark compares against.
    bool instanceMeshes = true;
};

/// The extensions this loader understands; any other entry of extensionsRequired is an error.
std::vector<std::string> supportedGltfExtensions();

/// Loads `path`. Non-fatal problems (dropped degenerate triangles, ignored point primitives) are
/// appended to `warnings`, one line per kind of problem.
Scene loadGltfScene(const std::string& path, std::vector<std::string>& warnings);
Scene loadGltfScene(const std::string& path, std::vector<std::string>& warnings, const SceneLoadOptions& options);

}  // namespace tessera
