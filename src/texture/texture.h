#pragma once
/// \file texture.h
/// A texture as glTF binds it to a material slot: an image, a texture-coordinate set, a sampler
/// (wrap and filter modes) and KHR_texture_transform; and the filtered lookup.
#include <cstdint>

#include "core/math.h"
#include "texture/image.h"

namespace tessera {

/// glTF sampler wrap modes (10497 REPEAT, 33648 MIRRORED_REPEAT, 33071 CLAMP_TO_EDGE).
enum class WrapMode : uint8_t { Repeat, MirroredRepeat, ClampToEdge };
/// Magnification filter; minification always uses the MIP level chosen from the footprint, with
/// this filter inside the level (glTF's minFilter *_MIPMAP_* variants collapse to it).
enum class FilterMode : uint8_t { Nearest, Linear };

/// KHR_texture_transform: uv' = T(offset) · R(rotation) · S(scale) · uv (the extension's matrix order).
struct TextureTransform {
    Vec2f offset{0.f}, scale{1.f};
    float rotation = 0.f;  ///< radians, counter-clockwise in uv space as the extension defines it
    bool identity() const { return offset == Vec2f(0.f) && scale == Vec2f(1.f) && rotation == 0.f; }
    Vec2f apply(Vec2f uv) const;
};

struct TextureRef {
    const Image* image = nullptr;  ///< owned by the Scene (stable address); null: slot unused
    uint8_t texCoord = 0;          ///< TEXCOORD_n set
    WrapMode wrapS = WrapMode::Repeat, wrapT = WrapMode::Repeat;
    FilterMode filter = FilterMode::Linear;
    TextureTransform transform;
    bool valid() const { return image != nullptr; }
};

/// Filtered lookup at texture coordinates `uv` (before the transform). `footprintUv` is the width of
/// the lookup in uv units (from the ray cone); 0 selects the finest level.
Vec4f sampleTexture(const TextureRef& tex, Vec2f uv, float footprintUv);

}  // namespace tessera
