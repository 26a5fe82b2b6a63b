#include "scene/camera.h"

#include <glm/gtc/matrix_transform.hpp>

#include "core/sampling.h"

namespace tessera {

Camera::Camera(const CameraDesc& desc, int width, int height) : desc_(desc), width_(width), height_(height) {
    Mat4d camToWorld(desc.cameraToWorld);
    Mat4d view = glm::inverse(camToWorld);
    // OpenGL-style projection (clip z in [−1, 1]); the far plane only has to be finite. Double
    // precision keeps the unprojection accurate even for a tiny znear.
    double aspect = double(width) / double(height);
    double zNear = desc.znear > 0.f ? desc.znear : 0.01;
    Mat4d proj = glm::perspective(double(desc.yfov), aspect, zNear, zNear * 1e4);
    viewProj_ = proj * view;
    invViewProj_ = glm::inverse(viewProj_);
    eye_ = Vec3f(camToWorld[3]);
    forward_ = glm::normalize(Vec3f(-camToWorld[2]));
    right_ = glm::normalize(Vec3f(camToWorld[0]));
    up_ = glm::normalize(Vec3f(camToWorld[1]));
    // Image-plane area at distance 1, from the same inverse view-projection generateRay uses: the
    // film corners unprojected onto the near plane, rescaled to unit distance along the view axis.
    auto corner = [&](double nx, double ny) {
        glm::dvec4 a = invViewProj_ * glm::dvec4(nx, ny, -1.0, 1.0);
        Vec3d d = Vec3d(a) / a.w - Vec3d(eye_);
        return d / glm::dot(d, Vec3d(forward_));
    };
    Vec3d lo = corner(-1.0, -1.0), hi = corner(1.0, 1.0);
    imagePlaneArea_ = float(std::abs(glm::dot(hi - lo, Vec3d(right_))) * std::abs(glm::dot(hi - lo, Vec3d(up_))));
    pixelSpreadAngle_ = float(std::abs(glm::dot(hi - lo, Vec3d(up_))) / double(height));
}

float Camera::importance(const Vec3f& pLens, const Vec3f& dir, Vec2f* raster) const {
    float cosTheta = glm::dot(dir, forward_);
    if (!(cosTheta > 0.f)) return 0.f;
    // The point the ray crosses on the plane of focus (pinhole: any point along the ray) projects
    // through the eye to the raster position, exactly inverting generateRay.
    float t = isPinhole() ? 1.f / cosTheta : desc_.focusDistance / cosTheta;
    Vec2f r;
    if (!worldToRaster(pLens + t * dir, r)) return 0.f;
    if (raster) *raster = r;
    float cos2 = cosTheta * cosTheta;
    return 1.f / (imagePlaneArea_ * lensArea() * cos2 * cos2);
}

void Camera::pdfEmission(const Vec3f& dir, float& pdfPosA, float& pdfDirW) const {
    float cosTheta = glm::dot(dir, forward_);
    pdfPosA = 1.f / lensArea();
    pdfDirW = cosTheta > 0.f ? 1.f / (imagePlaneArea_ * cosTheta * cosTheta * cosTheta) : 0.f;
}

bool Camera::sampleIncoming(const Vec3f& ref, Vec2f uLens, CameraSample& out) const {
    out.pLens = eye_;
    if (!isPinhole()) {
        Vec2f lens = desc_.apertureRadius * sampleConcentricDisk(uLens);
        out.pLens = eye_ + lens.x * right_ + lens.y * up_;
    }
    Vec3f toLens = out.pLens - ref;
    float dist2 = glm::dot(toLens, toLens);
    if (!(dist2 > 0.f)) return false;
    out.dist = std::sqrt(dist2);
    out.wiWorld = toLens / out.dist;
    out.We = importance(out.pLens, -out.wiWorld, &out.raster);
    if (!(out.We > 0.f)) return false;
    float cosTheta = glm::dot(-out.wiWorld, forward_);
    out.pdfW = dist2 / (cosTheta * lensArea());
    return true;
}

Ray Camera::generateRay(Vec2f raster, Vec2f uLens) const {
    // Raster → normalised device coordinates (x right, y up), then through the inverse
    // view-projection matrix to a world point A on the near plane (clip z = −1).
    double ndcX = 2.0 * double(raster.x) / width_ - 1.0;
    double ndcY = 1.0 - 2.0 * double(raster.y) / height_;
    glm::dvec4 a = invViewProj_ * glm::dvec4(ndcX, ndcY, -1.0, 1.0);
    Vec3d pointA = Vec3d(a) / a.w;
    Vec3f dir = Vec3f(glm::normalize(pointA - Vec3d(eye_)));
    Ray ray{eye_, dir, 0.f, kInfinity};
    if (desc_.apertureRadius > 0.f) {
        // Thin lens: every ray through the lens aperture meets the pinhole ray on the plane of focus
        // (perpendicular to the view axis at focusDistance).
        float tFocus = desc_.focusDistance / glm::dot(dir, forward_);
        Vec3f pFocus = eye_ + tFocus * dir;
        Vec2f lens = desc_.apertureRadius * sampleConcentricDisk(uLens);
        ray.o = eye_ + lens.x * right_ + lens.y * up_;
        ray.d = glm::normalize(pFocus - ray.o);
    }
    return ray;
}

bool Camera::worldToRaster(const Vec3f& p, Vec2f& raster) const {
    glm::dvec4 clip = viewProj_ * glm::dvec4(Vec3d(p), 1.0);
    if (clip.w <= 0.0) return false;
    double ndcX = clip.x / clip.w, ndcY = clip.y / clip.w;
    raster = Vec2f(float((ndcX + 1.0) * 0.5 * width_), float((1.0 - ndcY) * 0.5 * height_));
    return raster.x >= 0.f && raster.x <= float(width_) && raster.y >= 0.f && raster.y <= float(height_);
}

}  // namespace tessera
