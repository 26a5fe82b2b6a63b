#pragma once
/// \file gltf_lights.h
/// The light half of the glTF loader (internal to scene/): KHR_lights_punctual point, spot and
/// directional lights on nodes, and the root's TESSERA_environment; plus the checked reading of
/// JSON extension values (numbers, colours) that the loader shares.
#include <tiny_gltf.h>

#include <string>
#include <vector>

#include "core/math.h"
#include "scene/gltf_loader.h"

namespace tessera {

/// Checked reads of extension values of one file: a bad value throws SceneError naming `path`, the
/// element and the problem.
struct GltfValues {
    std::string path;
    [[noreturn]] void fail(const std::string& element, const std::string& problem) const;
    /// An optional RGB array member with components in [0, maxComponent].
    Rgb color3(const tinygltf::Value& obj, const char* key, const std::string& element, Rgb fallback, double maxComponent) const;
    /// An optional finite number member.
    double number(const tinygltf::Value& obj, const char* key, const std::string& element, double fallback) const;
};

/// The KHR_lights_punctual light `v` names on a node with transform `world`, appended to `scene`'s
/// point, spot or directional lights (unsupported types give a warning).
void readGltfPunctualLight(const tinygltf::Model& model, const GltfValues& values, const tinygltf::Value& v, const Mat4d& world,
                           const std::string& el, Scene& scene, std::vector<std::string>& warnings);

/// The root's TESSERA_environment, if any, into scene.environment (its image into scene.images);
/// `assetBytes` is the scene's running total of asset bytes read.
void readGltfEnvironment(const tinygltf::Model& model, const GltfValues& values, const SceneLoadOptions& options, uint64_t& assetBytes,
                         Scene& scene);

}  // namespace tessera
