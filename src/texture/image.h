#pragma once
/// \file image.h
/// Decoded texture images: linear RGBA float texels with their MIP pyramid, converted once at load
/// time from whatever the file holds (PNG, JPEG, EXR, HDR, decoded by OpenImageIO). sRGB-encoded
/// images (glTF colour textures) are decoded to linear here, so lookups never convert.
#include <cstdint>
#include <string>
#include <vector>

#include "core/math.h"

namespace tessera {

/// How the stored values map to linear ones: glTF colour textures (baseColor, emissive,
/// specularColor) are sRGB; data textures (metallicRoughness, normal, …) and float images are linear.
enum class ColorEncoding : uint8_t { Linear, Srgb };

struct ImageLevel {
    int width = 0, height = 0;
    std::vector<Vec4f> texels;  ///< row-major, row 0 at the top (v = 0, glTF's convention)
    const Vec4f& at(int x, int y) const { return texels[size_t(y) * size_t(width) + size_t(x)]; }
};

struct Image {
    std::string name;               ///< for messages: "images[3] (foo.png)"
    std::vector<ImageLevel> levels; ///< levels[0] is the full resolution; each next level halves
    int width() const { return levels.empty() ? 0 : levels[0].width; }
    int height() const { return levels.empty() ? 0 : levels[0].height; }
};

/// Limits on untrusted images, checked against the header before any pixel is allocated.
struct ImageDecodeLimits {
    uint64_t maxPixels = uint64_t(1) << 28;  ///< width × height
    uint64_t maxBytes = uint64_t(4) << 30;   ///< decoded float RGBA bytes incl. MIP levels
};

/// Decodes an encoded image held in memory (GLB buffer view, data URI). Throws InputError naming
/// `name` and the problem (not an image, truncated, header over the limits, …).
Image decodeImage(const std::string& name, const uint8_t* bytes, size_t size, ColorEncoding encoding,
                  const ImageDecodeLimits& limits = {});
/// Reads and decodes an image file (the caller has checked that the path may be read).
Image readImageFile(const std::string& path, ColorEncoding encoding, const ImageDecodeLimits& limits = {});
/// Fills levels[1..] from levels[0] (box filter; odd sizes handled). Called by the decoders.
void buildMipLevels(Image& image);

}  // namespace tessera
