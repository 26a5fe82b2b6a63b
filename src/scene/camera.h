#pragma once
/// \file camera.h
/// Pinhole and thin-lens cameras. Primary rays come from the inverse view-projection matrix: the
/// jittered raster position is unprojected to a world point A and the direction is A − eye
/// (the course brief's requirement; see Camera::generateRay).
#include "core/math.h"
#include "core/ray.h"

namespace tessera {

struct CameraDesc {
    Mat4f cameraToWorld{1.f};  ///< looks down its local −z, +y up (glTF convention)
    float yfov = 0.8f;         ///< vertical field of view, radians
    float znear = 0.01f;       ///< near plane of the projection (only sets where A is unprojected)
    float apertureRadius = 0.f;  ///< 0 = pinhole
    float focusDistance = 1.f;   ///< distance along the view axis that is in focus (thin lens)
};

/// The camera reached from a scene point (light tracing, BDPT's t = 1 strategy).
struct CameraSample {
    Vec3f pLens{0.f};   ///< point on the lens (the eye for a pinhole)
    Vec3f wiWorld{0.f}; ///< unit direction from the reference point towards pLens
    float dist = 0.f;   ///< distance from the reference point to pLens
    float We = 0.f;     ///< importance of the ray pLens → reference point
    float pdfW = 0.f;   ///< solid-angle density at the reference point of choosing pLens
    Vec2f raster{0.f};  ///< where the ray lands on the film
};

class Camera {
public:
    Camera(const CameraDesc& desc, int width, int height);

    /// Ray through raster position `raster` (pixels; (0,0) top-left corner, y down) with lens
    /// sample `uLens` in [0,1)². The direction is unit length.
    Ray generateRay(Vec2f raster, Vec2f uLens) const;
    /// Projects a world point to raster coordinates; false if it lies behind the camera or off film.
    bool worldToRaster(const Vec3f& p, Vec2f& raster) const;

    /// Importance We(pLens → pLens + dir) of a unit direction leaving lens point pLens, and its
    /// raster position. Normalised so that ∫ We cos θ dA dω over lens and film is 1: with A the
    /// area of the image rectangle at distance 1 along the view axis,
    ///     We = 1 / (A · lensArea · cos⁴θ)        (pbrt-v3 §16.1.1; Veach 1997, §8.1.2)
    /// because a ray through raster point r has solid-angle density 1 / (A cos³θ) (uniform on the
    /// image plane, Jacobian d²/cos θ with d = 1/cos θ) and the lens point 1/lensArea. Zero when the
    /// direction misses the film. A pinhole counts as lensArea = 1 (a delta in position).
    float importance(const Vec3f& pLens, const Vec3f& dir, Vec2f* raster = nullptr) const;
    /// Densities of generateRay: pdfPosA = 1/lensArea (1 for a pinhole), pdfDirW = 1 / (A cos³θ).
    void pdfEmission(const Vec3f& dir, float& pdfPosA, float& pdfDirW) const;
    /// Samples a lens point as seen from `ref` (uniform on the lens): pdfW = d² / (cos θ · lensArea).
    /// False when the point is behind the camera or projects off the film.
    bool sampleIncoming(const Vec3f& ref, Vec2f uLens, CameraSample& out) const;
    bool isPinhole() const { return !(desc_.apertureRadius > 0.f); }
    float lensArea() const { return isPinhole() ? 1.f : kPi * desc_.apertureRadius * desc_.apertureRadius; }

    /// Width in world units that one pixel subtends at distance |p − eye| from the camera: the
    /// texture footprint at p (pbrt-v4's Camera::Approximate_dp_dxy, isotropic and without the
    /// surface's tilt). A function of p alone, so every integrator, every bounce and every thread
    /// count sees the same MIP level at the same point.
    float pixelFootprint(const Vec3f& p) const { return glm::length(p - eye_) * pixelSpreadAngle_; }

    Vec3f position() const { return eye_; }
    Vec3f forward() const { return forward_; }
    int width() const { return width_; }
    int height() const { return height_; }
    const Mat4d& viewProjection() const { return viewProj_; }
    const Mat4d& inverseViewProjection() const { return invViewProj_; }

private:
    CameraDesc desc_;
    int width_, height_;
    Mat4d viewProj_, invViewProj_;
    Vec3f eye_, forward_, right_, up_;
    float imagePlaneArea_ = 0.f;  ///< area of the image rectangle at distance 1 in front of the eye
    float pixelSpreadAngle_ = 0.f;  ///< image-plane height at distance 1 over the pixel rows (radians, small-angle)
};

}  // namespace tessera
