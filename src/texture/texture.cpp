#include "texture/texture.h"

#include <cmath>

namespace tessera {

// KHR_texture_transform: matrix = T(offset) · R(rotation) · S(scale). The extension's worked example
// ("offset [0, 1], rotation π/2, scale ½ uses the lower left quadrant, rotated clockwise") fixes the
// rotation's sign: u' = cos·u + sin·v, v' = −sin·u + cos·v (what three.js and the Khronos sample
// viewer implement).
Vec2f TextureTransform::apply(Vec2f uv) const {
    Vec2f s = uv * scale;
    float c = std::cos(rotation), sn = std::sin(rotation);
    return Vec2f(c * s.x + sn * s.y, -sn * s.x + c * s.y) + offset;
}

namespace {

/// Texel index along an axis of n texels for an integer coordinate that may lie outside [0, n).
int wrapIndex(int i, int n, WrapMode mode) {
    switch (mode) {
    case WrapMode::Repeat: {
        int r = i % n;
        return r < 0 ? r + n : r;
    }
    case WrapMode::MirroredRepeat: {
        // Period 2n: 0 … n−1 then n−1 … 0 (OpenGL's MIRRORED_REPEAT).
        int period = 2 * n;
        int r = i % period;
        if (r < 0) r += period;
        return r < n ? r : period - 1 - r;
    }
    case WrapMode::ClampToEdge:
        return std::clamp(i, 0, n - 1);
    }
    return 0;
}

/// Coordinates far outside [0, 1] would overflow int after scaling; Repeat and MirroredRepeat are
/// periodic, so reduce them first (by whole mirror periods, 2, so both modes stay exact).
float reduceCoordinate(float x, WrapMode mode) {
    if (mode == WrapMode::ClampToEdge) return std::clamp(x, -1.f, 2.f);
    if (std::abs(x) < 1e6f) return x;
    return x - 2.f * std::floor(x * 0.5f);
}

Vec4f lookupNearest(const ImageLevel& level, Vec2f st, WrapMode ws, WrapMode wt) {
    int x = wrapIndex(int(std::floor(st.x * float(level.width))), level.width, ws);
    int y = wrapIndex(int(std::floor(st.y * float(level.height))), level.height, wt);
    return level.at(x, y);
}

/// Bilinear interpolation between the four texel centres around st (centres at (i + ½) / n).
Vec4f lookupBilinear(const ImageLevel& level, Vec2f st, WrapMode ws, WrapMode wt) {
    float x = st.x * float(level.width) - 0.5f, y = st.y * float(level.height) - 0.5f;
    float x0f = std::floor(x), y0f = std::floor(y);
    float fx = x - x0f, fy = y - y0f;
    int x0 = int(x0f), y0 = int(y0f);
    int xa = wrapIndex(x0, level.width, ws), xb = wrapIndex(x0 + 1, level.width, ws);
    int ya = wrapIndex(y0, level.height, wt), yb = wrapIndex(y0 + 1, level.height, wt);
    Vec4f top = (1.f - fx) * level.at(xa, ya) + fx * level.at(xb, ya);
    Vec4f bottom = (1.f - fx) * level.at(xa, yb) + fx * level.at(xb, yb);
    return (1.f - fy) * top + fy * bottom;
}

Vec4f lookupLevel(const TextureRef& tex, int level, Vec2f st) {
    const ImageLevel& l = tex.image->levels[size_t(level)];
    return tex.filter == FilterMode::Nearest ? lookupNearest(l, st, tex.wrapS, tex.wrapT)
                                             : lookupBilinear(l, st, tex.wrapS, tex.wrapT);
}

}  // namespace

Vec4f sampleTexture(const TextureRef& tex, Vec2f uv, float footprintUv) {
    if (!tex.valid() || tex.image->levels.empty()) return Vec4f(1.f);
    if (!tex.transform.identity()) {
        uv = tex.transform.apply(uv);
        // The footprint was measured in the mesh's uv units; the transform scales them (rotation and
        // offset do not change lengths).
        footprintUv *= std::max(std::abs(tex.transform.scale.x), std::abs(tex.transform.scale.y));
    }
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) uv = Vec2f(0.f);
    Vec2f st(reduceCoordinate(uv.x, tex.wrapS), reduceCoordinate(uv.y, tex.wrapT));

    // MIP level from the footprint (Williams 1983, "Pyramidal Parametrics"): the level whose texels
    // are as wide as the footprint, λ = log2(footprint in level-0 texels). Levels are blended
    // linearly (trilinear filtering), so the level choice never shows as a seam.
    const Image& img = *tex.image;
    int maxLevel = int(img.levels.size()) - 1;
    float texels = footprintUv * float(std::max(img.width(), img.height()));
    if (!(texels > 1.f) || maxLevel == 0) return lookupLevel(tex, 0, st);
    float lambda = std::min(std::log2(texels), float(maxLevel));
    if (tex.filter == FilterMode::Nearest) return lookupLevel(tex, int(std::lround(lambda)), st);
    int l0 = int(std::floor(lambda));
    float f = lambda - float(l0);
    if (l0 >= maxLevel || f == 0.f) return lookupLevel(tex, std::min(l0, maxLevel), st);
    return (1.f - f) * lookupLevel(tex, l0, st) + f * lookupLevel(tex, l0 + 1, st);
}

}  // namespace tessera
