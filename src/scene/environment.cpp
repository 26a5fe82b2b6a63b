#include "scene/environment.h"

#include "core/error.h"
#include "core/sampling.h"

namespace tessera {

std::unique_ptr<Image> readEnvironmentImage(const std::string& path) {
    throw InputError(path + ": environment images need the texture layer (not merged yet)");
}

Vec2f EnvironmentLight::directionToUv(const Vec3f& d) {
    float u = 0.5f + std::atan2(d.z, d.x) * (0.5f * kInvPi);
    float v = std::acos(std::clamp(d.y, -1.f, 1.f)) * kInvPi;
    return {u - std::floor(u), std::min(v, 0x1.fffffep-1f)};
}

Vec3f EnvironmentLight::uvToDirection(Vec2f uv) {
    float phi = 2.f * kPi * (uv.x - 0.5f), theta = kPi * uv.y;
    float sinTheta = std::sin(theta);
    return {sinTheta * std::cos(phi), std::cos(theta), sinTheta * std::sin(phi)};
}

// A rotation by +θ about +Y (right-handed) maps the environment's frame to the world: x' = x cos θ +
// z sin θ, z' = −x sin θ + z cos θ, so the image centre (+X) goes to −Z for θ = 90°.
Vec3f EnvironmentLight::toWorld(const Vec3f& l) const {
    return {l.x * cosRot_ + l.z * sinRot_, l.y, -l.x * sinRot_ + l.z * cosRot_};
}
Vec3f EnvironmentLight::toLocal(const Vec3f& w) const {
    return {w.x * cosRot_ - w.z * sinRot_, w.y, w.x * sinRot_ + w.z * cosRot_};
}

void EnvironmentLight::build(const EnvironmentDesc& desc) {
    scale_ = desc.color * desc.intensity;
    image_ = desc.image;
    float rad = desc.rotationDeg * (kPi / 180.f);
    cosRot_ = std::cos(rad);
    sinRot_ = std::sin(rad);
    distribution_ = Distribution2D();
    luminanceIntegral_ = 4.0 * kPi * double(luminance(scale_));
}

Rgb EnvironmentLight::lookup(Vec2f) const { return Rgb(1.f); }

Rgb EnvironmentLight::Le(const Vec3f& wLight) const {
    if (!image_) return scale_;
    return scale_ * lookup(directionToUv(toLocal(wLight)));
}

Vec3f EnvironmentLight::sample(Vec2f u, float& pdfW) const {
    if (distribution_.empty()) {
        pdfW = kUniformSpherePdfW;
        return sampleUniformSphere(u);
    }
    float su, sv, pdfUv;
    distribution_.sample(u.x, u.y, su, sv, pdfUv);
    // (u, v) ↦ direction has Jacobian |dω / du dv| = 2π · π · sin θ.
    float sinTheta = std::sin(kPi * sv);
    pdfW = sinTheta > 0.f ? pdfUv / (2.f * kPi * kPi * sinTheta) : 0.f;
    return toWorld(uvToDirection(Vec2f(su, sv)));
}

float EnvironmentLight::pdfW(const Vec3f& wLight) const {
    if (distribution_.empty()) return kUniformSpherePdfW;
    Vec3f local = toLocal(wLight);
    Vec2f uv = directionToUv(local);
    float sinTheta = safeSqrt(1.f - local.y * local.y);
    return sinTheta > 0.f ? distribution_.pdf(uv.x, uv.y) / (2.f * kPi * kPi * sinTheta) : 0.f;
}

}  // namespace tessera
