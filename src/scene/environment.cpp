#include "scene/environment.h"

#include "core/error.h"
#include "core/sampling.h"
#include "texture/texture.h"

namespace tessera {

std::unique_ptr<Image> readEnvironmentImage(const std::string& path) {
    auto image = std::make_unique<Image>(readImageFile(path, ColorEncoding::Linear));
    if (image->width() < 2 || image->height() < 1)
        throw InputError(path + ": an environment image needs at least 2x1 pixels, got " + std::to_string(image->width()) + "x" +
                         std::to_string(image->height()));
    // Radiance cannot be negative, but real HDRIs hold negative pixels: lossy EXR compression (DWA)
    // and resampling ring around the sun (Poly Haven's "sky" at 512x256 has values down to −3394
    // next to +22672). They are clamped to 0 (non-finite texels the texture layer already made 0).
    ImageLevel& level = image->levels[0];
    bool clamped = false;
    for (Vec4f& t : level.texels)
        for (int c = 0; c < 3; ++c)
            if (t[c] < 0.f) t[c] = 0.f, clamped = true;
    if (clamped) {
        image->levels.resize(1);
        buildMipLevels(*image);
    }
    image->name = path;
    return image;
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
    if (!image_) return;

    // Sampling weights: the luminance of the *bilinear* reconstruction that Le() returns, averaged
    // over each pixel's cell — in 1D the cell average of the interpolant is ⅛ p(i−1) + ¾ p(i) +
    // ⅛ p(i+1) (wrapping in u, clamped in v like the lookup) — so a cell is never given zero
    // probability where Le is non-zero (which would bias the estimate), times sin θ at the cell's
    // centre, the Jacobian of the lat-long map (pbrt-v4 §12.5.2).
    const ImageLevel& level = image_->levels[0];
    const int w = level.width, h = level.height;
    std::vector<float> lum(size_t(w) * size_t(h)), weights(size_t(w) * size_t(h));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const Vec4f& t = level.at(x, y);
            lum[size_t(y) * size_t(w) + size_t(x)] = std::max(0.f, luminance(scale_ * Rgb(t.r, t.g, t.b)));
        }
    const float k[3] = {0.125f, 0.75f, 0.125f};
    double integral = 0.0;
    for (int y = 0; y < h; ++y) {
        float sinTheta = std::sin(kPi * (float(y) + 0.5f) / float(h));
        for (int x = 0; x < w; ++x) {
            float avg = 0.f;
            for (int dy = -1; dy <= 1; ++dy) {
                int yy = std::clamp(y + dy, 0, h - 1);
                for (int dx = -1; dx <= 1; ++dx) {
                    int xx = (x + dx + w) % w;
                    avg += k[dy + 1] * k[dx + 1] * lum[size_t(yy) * size_t(w) + size_t(xx)];
                }
            }
            weights[size_t(y) * size_t(w) + size_t(x)] = avg * sinTheta;
            integral += double(avg) * sinTheta;
        }
    }
    distribution_ = Distribution2D(weights, w, h);
    luminanceIntegral_ = integral * (2.0 * kPi / w) * (kPi / h);  // Σ L sin θ Δφ Δθ
}

Rgb EnvironmentLight::lookup(Vec2f uv) const {
    TextureRef tex;
    tex.image = image_;
    tex.wrapS = WrapMode::Repeat;      // longitude wraps around
    tex.wrapT = WrapMode::ClampToEdge; // latitude stops at the poles
    tex.filter = FilterMode::Linear;
    Vec4f t = sampleTexture(tex, uv, 0.f);
    return Rgb(t.r, t.g, t.b);
}

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
