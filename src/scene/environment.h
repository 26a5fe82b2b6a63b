#pragma once
/// \file environment.h
/// The environment light: radiance arriving from infinitely far away, a constant colour or an
/// equirectangular (latitude–longitude) HDR image, importance-sampled by luminance × sin θ
/// (pbrt-v4 §12.5, ImageInfiniteLight).
///
/// Orientation (glTF world, +Y up), the convention of Blender's Environment Texture node and of the
/// Khronos glTF Sample Viewer (both checked against their sources): for a unit direction d in the
/// environment's frame,
///     u = 0.5 + atan2(d.z, d.x) / 2π      (column, left to right)
///     v = acos(d.y) / π                   (row, top to bottom)
/// so the top row is straight up (+Y), the bottom row straight down, the image centre (u, v) =
/// (½, ½) is the +X horizon, u = ¼ is −Z (what a default glTF camera looks at), u = ¾ is +Z and the
/// left/right edges are −X. Seen from inside, the image is not mirrored: turning right (from −Z
/// towards +X) moves right in the image. Blender's +X (the image centre) is glTF's +X and Blender's
/// +Y (u = ¼) is glTF's −Z, which is why Blender and the sample viewer show the same HDRI alike.
/// `rotationDeg` turns the environment about +Y, counter-clockwise seen from above (right-handed):
/// with 90° the image centre moves from +X to −Z.
#include <memory>
#include <string>

#include "core/distribution.h"
#include "core/math.h"
#include "texture/image.h"

namespace tessera {

/// What the scene (TESSERA_environment) or the command line (--env) asks for.
struct EnvironmentDesc {
    Rgb color{1.f};                ///< constant radiance, or the image's multiplier
    const Image* image = nullptr;  ///< linear RGB(A), owned by Scene::images; null: constant colour
    float intensity = 1.f;         ///< scale of the radiance
    float rotationDeg = 0.f;       ///< about +Y, counter-clockwise seen from above
    std::string source;            ///< file or "constant", for messages and metadata
};

/// Reads an equirectangular environment image (EXR, .hdr, … through the texture layer, linear).
/// Negative pixels (ringing of lossy compression) are clamped to 0, non-finite ones are 0 (texture
/// layer). Throws InputError naming the file when it cannot be read or is smaller than 2×1 pixels.
std::unique_ptr<Image> readEnvironmentImage(const std::string& path);

class EnvironmentLight {
public:
    void build(const EnvironmentDesc& desc);

    /// Radiance arriving from direction `wLight` (unit, world space, pointing away from the scene).
    Rgb Le(const Vec3f& wLight) const;
    /// A direction with density ∝ luminance(L) (times sin θ's Jacobian): pdfW in solid angle.
    Vec3f sample(Vec2f u, float& pdfW) const;
    /// The solid-angle density sample() has for `wLight`.
    float pdfW(const Vec3f& wLight) const;
    /// ∫ luminance(L) dω over the sphere (for light selection by power).
    double luminanceIntegral() const { return luminanceIntegral_; }

    /// The image coordinates (u right, v down, both in [0, 1)) of a unit direction in the
    /// environment's own frame, and back (the convention above).
    static Vec2f directionToUv(const Vec3f& local);
    static Vec3f uvToDirection(Vec2f uv);
    /// World ↔ environment frame (the rotation about +Y).
    Vec3f toLocal(const Vec3f& world) const;
    Vec3f toWorld(const Vec3f& local) const;

private:
    Rgb lookup(Vec2f uv) const;

    Rgb scale_{0.f};
    const Image* image_ = nullptr;
    float cosRot_ = 1.f, sinRot_ = 0.f;
    Distribution2D distribution_;  ///< over (u, v): cell luminance × sin θ (images only)
    double luminanceIntegral_ = 0.0;
};

}  // namespace tessera
