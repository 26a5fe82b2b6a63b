#pragma once
/// \file gltf_files.h
/// File access for tinygltf (internal to the glTF loader), confined to the scene's folder. Replaces
/// tinygltf's defaults, whose path expansion runs wordexp(3) on URIs taken from the file
/// (shell-style expansion of untrusted text) and which read any path a URI names.
#include <tiny_gltf.h>

#include <filesystem>
#include <map>
#include <string>

#include "scene/gltf_loader.h"

namespace tessera {

struct GltfFileAccess {
    std::filesystem::path root;  ///< canonical folder of the scene file
    SceneLoadOptions options;
    std::string violation;       ///< first refused path, reported as the error's cause
    std::map<std::string, std::string> refusals;  ///< canonical path -> why it was refused (image messages)

    /// tinygltf's file callbacks, reading through this object (which must outlive the load).
    tinygltf::FsCallbacks callbacks();
    /// True when `path` may be read; otherwise records why not.
    bool allowed(const std::string& path);
    void refuse(const std::string& path, const std::string& why);
    /// Why `path` was refused, or "" when it was not.
    std::string whyRefused(const std::string& path) const;
};

}  // namespace tessera
