#include "scene/lights.h"

#include "core/frame.h"
#include "core/sampling.h"
#include "geometry/intersect.h"
#include "texture/texture.h"

namespace tessera {
namespace {
/// Uniform point (pdfA = 1/area) on triangle `primId` of `mesh`, with its unit geometric normal and
/// its barycentrics (u, v) of vertices 1 and 2 (Hit's convention).
void samplePointOnTriangle(const TriangleMesh& mesh, uint32_t primId, Vec2f u, Vec3f& p, Vec3f& n, Vec2f& bary) {
    const glm::uvec3& t = mesh.triangles[primId];
    const Vec3f &p0 = mesh.positions[t.x], &p1 = mesh.positions[t.y], &p2 = mesh.positions[t.z];
    Vec2f b = sampleUniformTriangle(u);
    p = b.x * p0 + b.y * p1 + (1.f - b.x - b.y) * p2;
    n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
    bary = Vec2f(b.y, 1.f - b.x - b.y);
}

/// The emissive texture's mean over a triangle, from 16 stratified points (uniform by area): the
/// weight of the triangle's power in light selection. Within the triangle points stay uniform by
/// area, so a texture that varies inside one triangle costs variance, never correctness.
Rgb meanTextureOverTriangle(const TextureRef& tex, const TriangleMesh& mesh, int set, uint32_t primId) {
    Rgb sum(0.f);
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) {
            Vec2f b = sampleUniformTriangle(Vec2f((float(i) + 0.5f) / 4.f, (float(j) + 0.5f) / 4.f));
            Vec4f t = sampleTexture(tex, mesh.texcoordAt(set, primId, b.y, 1.f - b.x - b.y), 0.f);
            sum += Rgb(t.r, t.g, t.b);
        }
    return sum / 16.f;
}
/// Below sin²θmax = sin²(1.5°) the cone's 1 − cos θmax cancels catastrophically in float: use the
/// series 1 − cos θ ≈ sin²θ / 2 instead (the same threshold pbrt-v4 uses).
constexpr float kSmallConeSin2 = 0.00068523f;
}

void LightSet::build(const SceneGeometry& geometry, const std::vector<Material>& materials,
                     const std::vector<PointLightDesc>& pointLights, const std::vector<SpotLightDesc>& spotLights,
                     const std::vector<DirectionalLightDesc>& directionalLights, const EnvironmentDesc* environment) {
    geometry_ = &geometry;
    lights_.clear();
    environmentIndex_ = kInvalidId;
    meshFirstLight_.assign(geometry.meshes.size(), kInvalidId);
    sphereLight_.assign(geometry.spheres.size(), kInvalidId);
    meshEmissive_.assign(geometry.meshes.size(), TextureRef{});

    // The scene's bounding sphere (of the geometry, as pbrt's): infinite lights emit from a disk of
    // its radius and their power is measured through it. Padded so that the disk's rays start
    // strictly outside every primitive.
    Bounds3f bounds;
    for (const TriangleMesh& mesh : geometry.meshes)
        for (const Vec3f& p : mesh.positions) bounds.extend(p);
    for (const Sphere& s : geometry.spheres) bounds.extend(sphereBounds(s));
    sceneCenter_ = bounds.empty() ? Vec3f(0.f) : bounds.center();
    sceneRadius_ = bounds.empty() ? 1.f : 0.5f * glm::length(bounds.diagonal());
    sceneRadius_ = std::max(sceneRadius_ * 1.01f, 1e-3f);

    std::vector<float> power;
    for (uint32_t g = 0; g < geometry.meshes.size(); ++g) {
        const TriangleMesh& mesh = geometry.meshes[g];
        const Material& mat = materials[mesh.materialId];
        if (!mat.isEmissive()) continue;
        // Every triangle of an emissive mesh gets a light slot, even a zero-area one, so that
        // lightIndexOf is a plain offset; zero-area ones get zero power and are never picked.
        meshFirstLight_[g] = uint32_t(lights_.size());
        // An emissive texture (glTF emissiveTexture, sRGB-decoded) multiplies the emission per point;
        // without texture coordinates it is read at (0, 0), as the material code does.
        const TextureRef& tex = mat.textures.emissive;
        if (tex.valid()) meshEmissive_[g] = tex;
        for (uint32_t i = 0; i < mesh.triangles.size(); ++i) {
            const glm::uvec3& t = mesh.triangles[i];
            float area = 0.5f * glm::length(glm::cross(mesh.positions[t.y] - mesh.positions[t.x],
                                                       mesh.positions[t.z] - mesh.positions[t.x]));
            Light l{LightType::Triangle, g, i, mat.emission, mat.doubleSided, area};
            lights_.push_back(l);
            // A textured triangle keeps at least 1/1000 of its untextured power: its 16 lookups may all
            // miss a small bright texel, and a light that emits with selection probability 0 would
            // break BDPT's weights (its density 0 reads as a delta there); next-event estimation
            // alone would stay unbiased through BSDF hits.
            float lum = luminance(mat.emission);
            if (tex.valid()) lum = std::max(luminance(mat.emission * meanTextureOverTriangle(tex, mesh, tex.texCoord, i)), 1e-3f * lum);
            power.push_back(lum * area * kPi * (mat.doubleSided ? 2.f : 1.f));
        }
    }
    for (uint32_t i = 0; i < geometry.spheres.size(); ++i) {
        const Sphere& s = geometry.spheres[i];
        const Material& mat = materials[s.materialId];
        if (!mat.isEmissive()) continue;
        sphereLight_[i] = uint32_t(lights_.size());
        float area = 4.f * kPi * s.radius * s.radius;
        lights_.push_back(Light{LightType::Sphere, geometry.sphereGeomId(), i, mat.emission, mat.doubleSided, area});
        power.push_back(luminance(mat.emission) * area * kPi * (mat.doubleSided ? 2.f : 1.f));
    }
    for (const PointLightDesc& pl : pointLights) {
        Light l;
        l.type = LightType::Point;
        l.Le = pl.intensity;
        l.position = pl.position;
        lights_.push_back(l);
        power.push_back(luminance(pl.intensity) * 4.f * kPi);  // Φ = 4π I for an isotropic point source
    }
    for (const SpotLightDesc& sl : spotLights) {
        Light l;
        l.type = LightType::Spot;
        l.Le = sl.intensity;
        l.position = sl.position;
        l.direction = glm::normalize(sl.direction);
        l.cosInner = std::cos(sl.innerConeAngle);
        l.cosOuter = std::cos(sl.outerConeAngle);
        lights_.push_back(l);
        // Φ = I ∫ falloff dω = 2π I [(1 − cos inner) + (cos inner − cos outer) / 3]: the falloff t²
        // is quadratic in cos θ, so its integral over the transition band is a third of the band.
        power.push_back(luminance(sl.intensity) * 2.f * kPi * ((1.f - l.cosInner) + (l.cosInner - l.cosOuter) / 3.f));
    }
    const float diskArea = kPi * sceneRadius_ * sceneRadius_;
    for (const DirectionalLightDesc& dl : directionalLights) {
        Light l;
        l.type = LightType::Directional;
        l.Le = dl.irradiance;
        l.direction = glm::normalize(dl.direction);
        lights_.push_back(l);
        power.push_back(luminance(dl.irradiance) * diskArea);  // Φ = π r² E through the scene's disk
    }
    if (environment) {
        environment_.build(*environment);
        environmentIndex_ = uint32_t(lights_.size());
        Light l;
        l.type = LightType::Environment;
        lights_.push_back(l);
        power.push_back(float(environment_.luminanceIntegral() * diskArea));  // Φ = π r² ∫ L dω (pbrt-v4)
    }
    selection_ = Distribution1D(power);
}

uint32_t LightSet::lightIndexOf(uint32_t geomId, uint32_t primId) const {
    if (geomId < meshFirstLight_.size()) {
        uint32_t first = meshFirstLight_[geomId];
        return first == kInvalidId ? kInvalidId : first + primId;
    }
    if (geometry_ && geomId == geometry_->sphereGeomId() && primId < sphereLight_.size()) return sphereLight_[primId];
    return kInvalidId;
}

Rgb LightSet::intensityTowards(const Light& l, const Vec3f& w) const {
    if (l.type == LightType::Point) return l.Le;
    return l.Le * spotFalloff(glm::dot(l.direction, w), l.cosInner, l.cosOuter);
}

Rgb LightSet::radianceAt(uint32_t index, Vec2f bary) const {
    const Light& l = lights_[index];
    if (l.type != LightType::Triangle || !meshEmissive_[l.geomId].valid()) return l.Le;
    const TextureRef& tex = meshEmissive_[l.geomId];
    Vec4f t = sampleTexture(tex, geometry_->meshes[l.geomId].texcoordAt(tex.texCoord, l.primId, bary.x, bary.y), 0.f);
    return l.Le * Rgb(t.r, t.g, t.b);
}

Rgb LightSet::emitted(uint32_t index, const Vec3f& n, const Vec3f& w, Vec2f bary) const {
    const Light& l = lights_[index];
    switch (l.type) {
    case LightType::Triangle:
    case LightType::Sphere: return (l.twoSided || glm::dot(n, w) > 0.f) ? radianceAt(index, bary) : Rgb(0.f);
    case LightType::Point:
    case LightType::Spot: return intensityTowards(l, w);
    case LightType::Directional: return l.Le;
    case LightType::Environment: return environment_.Le(-w);
    }
    return Rgb(0.f);
}

float LightSet::environmentPdfW(const Vec3f& wLight) const {
    return hasEnvironment() ? selection_.pmf(environmentIndex_) * environment_.pdfW(wLight) : 0.f;
}

uint32_t LightSet::pick(float uPick) const {
    uint32_t index = selection_.sampleDiscrete(uPick);
    return selection_.pmf(index) == 0.f ? kInvalidId : index;
}

bool LightSet::sample(const Vec3f& ref, float uPick, Vec2f u, LightSample& out) const {
    if (lights_.empty()) return false;
    uint32_t index = pick(uPick);
    if (index == kInvalidId) return false;
    out.index = index;
    const Light& l = lights_[index];
    const float pmf = selection_.pmf(index);
    out.isInfinite = false;
    switch (l.type) {
    case LightType::Point:
    case LightType::Spot: {
        // Delta position: the "density" is the discrete selection probability and the incident
        // radiance integrates to the irradiance I / d² (inverse-square law).
        out.p = l.position;
        out.n = Vec3f(0.f);
        Vec3f d = l.position - ref;
        float dist2 = glm::dot(d, d);
        if (!(dist2 > 0.f)) return false;
        out.wi = d / std::sqrt(dist2);
        out.Le = intensityTowards(l, -out.wi) / dist2;
        out.pdfW = pmf;
        out.isDelta = true;
        return true;
    }
    case LightType::Directional:
    case LightType::Environment: {
        float pdfW = 1.f;
        out.wi = l.type == LightType::Directional ? -l.direction : environment_.sample(u, pdfW);
        out.Le = l.type == LightType::Directional ? l.Le : environment_.Le(out.wi);
        out.pdfW = pmf * pdfW;
        out.isDelta = l.type == LightType::Directional;
        out.isInfinite = true;
        out.n = Vec3f(0.f);
        out.p = ref + (2.f * sceneRadius_ + glm::length(ref - sceneCenter_)) * out.wi;
        return out.pdfW > 0.f;
    }
    case LightType::Triangle:
    case LightType::Sphere: break;
    }
    float pdfW = sampleOne(index, ref, u, out);
    if (!(pdfW > 0.f) || !std::isfinite(pdfW)) return false;
    out.pdfW = pdfW * pmf;
    out.isDelta = false;
    Vec3f d = out.p - ref;
    float len = glm::length(d);
    if (!(len > 0.f)) return false;
    out.wi = d / len;
    out.Le = emitted(index, out.n, -out.wi, out.bary);
    return true;
}

bool LightSet::sampleInfiniteEmission(uint32_t index, Vec2f uPos, Vec2f uDir, LightEmission& out) const {
    // Direction first, then the origin on the disk of radius r through the scene's centre
    // perpendicular to it, moved r towards the light so the ray starts outside the scene
    // (pbrt-v4 §12.5 ImageInfiniteLight::SampleLe; Veach 1997 §10.2 for the densities).
    const Light& l = lights_[index];
    float pdfDirW = 1.f;
    Vec3f wLight = l.type == LightType::Directional ? -l.direction : environment_.sample(uDir, pdfDirW);
    Frame frame(wLight);
    Vec2f disk = sampleConcentricDisk(uPos);
    out.p = sceneCenter_ + sceneRadius_ * (disk.x * frame.s + disk.y * frame.t + wLight);
    out.n = Vec3f(0.f);
    out.dir = -wLight;
    out.Le = l.type == LightType::Directional ? l.Le : environment_.Le(wLight);
    out.pdfPosA = diskPdfA();
    out.pdfDirW = selection_.pmf(index) * pdfDirW;
    out.isDeltaPos = false;
    out.isInfinite = true;
    return out.pdfDirW > 0.f;
}

bool LightSet::sampleEmission(float uPick, Vec2f uPos, Vec2f uDir, LightEmission& out) const {
    if (lights_.empty()) return false;
    uint32_t index = pick(uPick);
    if (index == kInvalidId) return false;
    const Light& l = lights_[index];
    out.index = index;
    out.isInfinite = false;
    switch (l.type) {
    case LightType::Point:
    case LightType::Spot:
        out.p = l.position;
        out.n = Vec3f(0.f);
        if (l.type == LightType::Point) {
            out.dir = sampleUniformSphere(uDir);
        } else {
            // Uniform in the outer cone (pbrt-v4 SpotLight::SampleLe); the falloff weights the ray.
            float cosTheta = 1.f - uDir.x * (1.f - l.cosOuter);
            float sinTheta = safeSqrt(1.f - cosTheta * cosTheta), phi = 2.f * kPi * uDir.y;
            out.dir = glm::normalize(Frame(l.direction).toWorld(Vec3f(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta)));
        }
        out.Le = intensityTowards(l, out.dir);
        out.isDeltaPos = true;
        pdfEmission(index, out.n, out.dir, out.pdfPosA, out.pdfDirW);
        return out.pdfDirW > 0.f;
    case LightType::Directional:
    case LightType::Environment: return sampleInfiniteEmission(index, uPos, uDir, out);
    case LightType::Triangle:
    case LightType::Sphere: break;
    }
    if (l.type == LightType::Triangle) {
        samplePointOnTriangle(geometry_->meshes[l.geomId], l.primId, uPos, out.p, out.n, out.bary);
    } else {
        const Sphere& s = geometry_->spheres[l.primId];
        out.n = sampleUniformSphere(uPos);
        out.p = sphereSurfacePoint(s.center, s.radius, s.center + s.radius * out.n);
    }
    // Direction: cosine-weighted about the emitting face. A two-sided emitter picks a face with
    // probability ½, reusing uDir.x so the sample stays stratified.
    Vec3f face = out.n;
    Vec2f u = uDir;
    if (l.twoSided) {
        if (u.x < 0.5f) {
            u.x *= 2.f;
        } else {
            u.x = std::min(2.f * u.x - 1.f, kOneMinusEpsilon);
            face = -face;
        }
    }
    Frame frame(face);
    Vec3f local = sampleCosineHemisphere(u);
    if (!(local.z > 0.f)) return false;
    out.dir = glm::normalize(frame.toWorld(local));
    out.Le = radianceAt(index, out.bary);
    out.isDeltaPos = false;
    pdfEmission(index, out.n, out.dir, out.pdfPosA, out.pdfDirW);
    return out.pdfPosA > 0.f && out.pdfDirW > 0.f;
}

void LightSet::pdfEmission(uint32_t index, const Vec3f& n, const Vec3f& dir, float& pdfPosA, float& pdfDirW) const {
    const Light& l = lights_[index];
    const float pmf = selection_.pmf(index);
    switch (l.type) {
    case LightType::Point:
        pdfPosA = pmf;
        pdfDirW = kUniformSpherePdfW;
        return;
    case LightType::Spot:
        pdfPosA = pmf;
        pdfDirW = glm::dot(dir, l.direction) >= l.cosOuter ? 1.f / (2.f * kPi * (1.f - l.cosOuter)) : 0.f;
        return;
    case LightType::Directional:
        pdfPosA = diskPdfA();
        pdfDirW = pmf;  // a delta in direction: only the selection is a density
        return;
    case LightType::Environment:
        pdfPosA = diskPdfA();
        pdfDirW = pmf * environment_.pdfW(-dir);
        return;
    case LightType::Triangle:
    case LightType::Sphere: break;
    }
    pdfPosA = l.area > 0.f ? pmf / l.area : 0.f;
    float c = glm::dot(n, dir);
    if (l.twoSided) pdfDirW = 0.5f * std::abs(c) * kInvPi;
    else pdfDirW = c > 0.f ? c * kInvPi : 0.f;
}

float LightSet::pdfW(uint32_t index, const Vec3f& ref, const Vec3f& pLight, const Vec3f& nLight) const {
    const Light& l = lights_[index];
    if (l.type == LightType::Environment) return environmentPdfW(glm::normalize(pLight - ref));
    return selection_.pmf(index) * pdfOneW(index, ref, pLight, nLight);
}

float LightSet::sampleOne(uint32_t index, const Vec3f& ref, Vec2f u, LightSample& out) const {
    const Light& l = lights_[index];
    if (l.type == LightType::Triangle) {
        samplePointOnTriangle(geometry_->meshes[l.geomId], l.primId, u, out.p, out.n, out.bary);
        return pdfOneW(index, ref, out.p, out.n);
    }
    const Sphere& s = geometry_->spheres[l.primId];
    Vec3d toCenter = Vec3d(s.center) - Vec3d(ref);
    double dc2 = glm::dot(toCenter, toCenter);
    double r2 = double(s.radius) * s.radius;
    if (dc2 <= r2) {
        // Inside the sphere every point is visible: sample its area uniformly.
        out.n = sampleUniformSphere(u);
        out.p = sphereSurfacePoint(s.center, s.radius, s.center + s.radius * out.n);
        return pdfOneW(index, ref, out.p, out.n);
    }
    // Outside: sample the cone of directions the sphere subtends uniformly and find the visible point
    // that direction hits (Shirley & Wang 1992; the closed form for the point is pbrt-v4's
    // Sphere::Sample, via the angle α at the centre instead of a ray–sphere test).
    float dc = float(std::sqrt(dc2));
    float sinThetaMax = s.radius / dc;
    float sin2ThetaMax = sinThetaMax * sinThetaMax;
    float cosThetaMax = safeSqrt(1.f - sin2ThetaMax);
    float oneMinusCos = 1.f - cosThetaMax;
    float cosTheta = (cosThetaMax - 1.f) * u.x + 1.f;
    float sin2Theta = 1.f - cosTheta * cosTheta;
    if (sin2ThetaMax < kSmallConeSin2) {
        sin2Theta = sin2ThetaMax * u.x;
        cosTheta = std::sqrt(1.f - sin2Theta);
        oneMinusCos = sin2ThetaMax / 2.f;
    }
    float cosAlpha = sin2Theta / sinThetaMax + cosTheta * safeSqrt(1.f - sin2Theta / sin2ThetaMax);
    float sinAlpha = safeSqrt(1.f - cosAlpha * cosAlpha);
    float phi = 2.f * kPi * u.y;
    Frame frame(Vec3f(glm::normalize(-toCenter)));  // z axis: from the centre towards ref
    Vec3f nLocal(sinAlpha * std::cos(phi), sinAlpha * std::sin(phi), cosAlpha);
    out.n = glm::normalize(frame.toWorld(nLocal));
    out.p = sphereSurfacePoint(s.center, s.radius, s.center + s.radius * out.n);
    return 1.f / (2.f * kPi * oneMinusCos);
}

float LightSet::pdfOneW(uint32_t index, const Vec3f& ref, const Vec3f& pLight, const Vec3f& nLight) const {
    const Light& l = lights_[index];
    if (isDelta(index)) return 0.f;  // a delta light is never hit by a ray
    if (l.type == LightType::Sphere) {
        const Sphere& s = geometry_->spheres[l.primId];
        Vec3d toCenter = Vec3d(s.center) - Vec3d(ref);
        double dc2 = glm::dot(toCenter, toCenter);
        double r2 = double(s.radius) * s.radius;
        if (dc2 > r2) {
            float sin2ThetaMax = float(r2 / dc2);
            float oneMinusCos = sin2ThetaMax < kSmallConeSin2 ? sin2ThetaMax / 2.f : 1.f - safeSqrt(1.f - sin2ThetaMax);
            return 1.f / (2.f * kPi * oneMinusCos);
        }
    }
    // Area sampling: convert 1/area to solid angle with d² / |cos θ_light| (Veach 1997, eq. 8.10).
    if (!(l.area > 0.f)) return 0.f;
    Vec3f d = pLight - ref;
    float dist2 = glm::dot(d, d);
    float cosLight = std::abs(glm::dot(nLight, d)) / std::sqrt(dist2);
    if (cosLight == 0.f) return 0.f;
    return dist2 / (cosLight * l.area);
}

}  // namespace tessera
