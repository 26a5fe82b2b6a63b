#pragma once
/// \file gltf_textures.h
/// The texture half of the glTF loader (internal to scene/): images (GLB buffer views, data URIs,
/// files next to the scene), textures and samplers, KHR_texture_transform, and a material's
/// texture slots and alpha mode. Images are decoded here, once per (image, colour encoding), by
/// decodeImage under ImageDecodeLimits; tinygltf's own decoders are never used (the loader's
/// tinygltf callback, storeImageBytes, only keeps the bytes).
#include <tiny_gltf.h>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "geometry/alpha_mask.h"
#include "materials/material.h"
#include "texture/image.h"

namespace tessera {

/// tinygltf image callback: keeps the encoded bytes of URI images (files, data URIs) in
/// image->image and decodes nothing. Buffer-view images are read later by GltfTextureReader,
/// after their view has been checked against its buffer (tinygltf passes such bytes unchecked).
bool storeImageBytes(tinygltf::Image* image, int index, std::string* err, std::string* warn, int, int,
                     const unsigned char* bytes, int size, void*);

class GltfTextureReader {
public:
    /// `whyUnreadable(path)`: the loader's reason for refusing to read `path` (outside the scene's
    /// folder, over the size limit), or "" when it did not refuse it. `memoryBudget`: the most
    /// bytes all decoded images together may take (--max-memory).
    GltfTextureReader(const tinygltf::Model& model, std::string scenePath, std::vector<std::unique_ptr<Image>>& images,
                      std::vector<std::string>& warnings, std::function<std::string(const std::string&)> whyUnreadable,
                      uint64_t memoryBudget);

    /// Fills `m.textures` and the alpha fields from `gm`; `el` names the material in messages.
    /// Throws SceneError naming the file, the material, the texture slot and the problem.
    void readMaterial(const tinygltf::Material& gm, Material& m, const std::string& el);

    /// The alpha mask a mesh of material `m` needs (shared by all its meshes), or null for opaque
    /// materials and masks that keep every hit.
    static std::shared_ptr<const AlphaMask> alphaMaskOf(const Material& m);

    /// Bytes of decoded images so far.
    uint64_t decodedBytes() const { return decodedBytes_; }

private:
    struct Slot;
    TextureRef readTexture(const Slot& slot, ColorEncoding encoding, const std::string& el);
    const Image* image(int index, ColorEncoding encoding, const std::string& el);
    [[noreturn]] void fail(const std::string& element, const std::string& problem) const;

    const tinygltf::Model& model_;
    std::string path_;
    std::vector<std::unique_ptr<Image>>& images_;
    std::vector<std::string>& warnings_;
    std::function<std::string(const std::string&)> whyUnreadable_;
    uint64_t memoryBudget_;
    uint64_t decodedBytes_ = 0;
    std::map<std::pair<int, ColorEncoding>, const Image*> decoded_;
    bool warnedBlend_ = false;
};

}  // namespace tessera
