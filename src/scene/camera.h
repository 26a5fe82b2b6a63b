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

class Camera {
public:
    Camera(const CameraDesc& desc, int width, int height);

    /// Ray through raster position `raster` (pixels; (0,0) top-left corner, y down) with lens
    /// sample `uLens` in [0,1)². The direction is unit length.
    Ray generateRay(Vec2f raster, Vec2f uLens) const;
    /// Projects a world point to raster coordinates; false if it lies behind the camera or off film.
    bool worldToRaster(const Vec3f& p, Vec2f& raster) const;

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
};

}  // namespace tessera
