#pragma once
// Synthetic equirectangular environment images for the tests (in memory, or written as EXR).
#include <functional>
#include <memory>

#include "texture/image.h"

namespace tessera::test {

/// A w × h linear image whose pixel (x, y) (y = 0 at the top) is f(x, y), with its MIP pyramid.
inline std::unique_ptr<Image> makeEnvironmentImage(int w, int h, const std::function<Rgb(int, int)>& f) {
    auto image = std::make_unique<Image>();
    image->name = "synthetic environment";
    ImageLevel level;
    level.width = w;
    level.height = h;
    level.texels.resize(size_t(w) * size_t(h));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            Rgb c = f(x, y);
            level.texels[size_t(y) * size_t(w) + size_t(x)] = Vec4f(c.r, c.g, c.b, 1.f);
        }
    image->levels.push_back(std::move(level));
    buildMipLevels(*image);
    return image;
}

/// A bright 2×2 spot at pixel (34, 9) of 64 × 32 (above the horizon) over a gradient in both
/// directions: the non-uniform image the sampling tests use.
inline std::unique_ptr<Image> spotAndGradientImage() {
    return makeEnvironmentImage(64, 32, [](int x, int y) {
        bool spot = (x == 34 || x == 35) && (y == 9 || y == 10);
        float g = 0.1f + float(x) / 64.f * (1.f + 2.f * float(y) / 32.f);
        return spot ? Rgb(400.f, 300.f, 200.f) : Rgb(g, 0.5f * g, 0.8f);
    });
}

}  // namespace tessera::test
