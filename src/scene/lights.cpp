#include "scene/lights.h"

#include "core/frame.h"
#include "core/sampling.h"
#include "geometry/intersect.h"

namespace tessera {
namespace {
/// Uniform point (pdfA = 1/area) on triangle `primId` of `mesh`, with its unit geometric normal.
void samplePointOnTriangle(const TriangleMesh& mesh, uint32_t primId, Vec2f u, Vec3f& p, Vec3f& n) {
    const glm::uvec3& t = mesh.triangles[primId];
    const Vec3f &p0 = mesh.positions[t.x], &p1 = mesh.positions[t.y], &p2 = mesh.positions[t.z];
    Vec2f b = sampleUniformTriangle(u);
    p = b.x * p0 + b.y * p1 + (1.f - b.x - b.y) * p2;
    n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
}
/// Below sin²θmax = sin²(1.5°) the cone's 1 − cos θmax cancels catastrophically in float: use the
/// series 1 − cos θ ≈ sin²θ / 2 instead (the same threshold pbrt-v4 uses).
constexpr float kSmallConeSin2 = 0.00068523f;
}

void LightSet::build(const SceneGeometry& geometry, const std::vector<Material>& materials,
                     const std::vector<PointLightDesc>& pointLights) {
    geometry_ = &geometry;
    lights_.clear();
    meshFirstLight_.assign(geometry.meshes.size(), kInvalidId);
    sphereLight_.assign(geometry.spheres.size(), kInvalidId);
    std::vector<float> power;
    for (uint32_t g = 0; g < geometry.meshes.size(); ++g) {
        const TriangleMesh& mesh = geometry.meshes[g];
        const Material& mat = materials[mesh.materialId];
        if (!mat.isEmissive()) continue;
        // Every triangle of an emissive mesh gets a light slot, even a zero-area one, so that
        // lightIndexOf is a plain offset; zero-area ones get zero power and are never picked.
        meshFirstLight_[g] = uint32_t(lights_.size());
        for (uint32_t i = 0; i < mesh.triangles.size(); ++i) {
            const glm::uvec3& t = mesh.triangles[i];
            float area = 0.5f * glm::length(glm::cross(mesh.positions[t.y] - mesh.positions[t.x],
                                                       mesh.positions[t.z] - mesh.positions[t.x]));
            Light l{LightType::Triangle, g, i, mat.emission, mat.doubleSided, area};
            lights_.push_back(l);
            power.push_back(luminance(mat.emission) * area * kPi * (mat.doubleSided ? 2.f : 1.f));
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
    double total = 0.0;
    for (float p : power) total += std::max(0.f, p);
    pmf_.assign(lights_.size(), 0.f);
    cdf_.assign(lights_.size(), 0.f);
    double acc = 0.0;
    for (size_t i = 0; i < lights_.size(); ++i) {
        double p = total > 0.0 ? std::max(0.f, power[i]) / total : 1.0 / double(lights_.size());
        pmf_[i] = float(p);
        acc += p;
        cdf_[i] = float(acc);
    }
    if (!cdf_.empty()) cdf_.back() = 1.f;
}

uint32_t LightSet::lightIndexOf(uint32_t geomId, uint32_t primId) const {
    if (geomId < meshFirstLight_.size()) {
        uint32_t first = meshFirstLight_[geomId];
        return first == kInvalidId ? kInvalidId : first + primId;
    }
    if (geometry_ && geomId == geometry_->sphereGeomId() && primId < sphereLight_.size()) return sphereLight_[primId];
    return kInvalidId;
}

Rgb LightSet::emitted(uint32_t index, const Vec3f& n, const Vec3f& w) const {
    const Light& l = lights_[index];
    return (l.twoSided || glm::dot(n, w) > 0.f) ? l.Le : Rgb(0.f);
}

uint32_t LightSet::pick(float uPick) const {
    uint32_t index = uint32_t(std::upper_bound(cdf_.begin(), cdf_.end(), uPick) - cdf_.begin());
    index = std::min<uint32_t>(index, uint32_t(lights_.size() - 1));
    while (pmf_[index] == 0.f && index > 0) --index;  // uPick landed on a zero-power entry's edge
    return pmf_[index] == 0.f ? kInvalidId : index;
}

bool LightSet::sample(const Vec3f& ref, float uPick, Vec2f u, LightSample& out) const {
    if (lights_.empty()) return false;
    uint32_t index = pick(uPick);
    if (index == kInvalidId) return false;
    out.index = index;
    const Light& l = lights_[index];
    if (l.type == LightType::Point) {
        // Delta position: the "density" is the discrete selection probability and the incident
        // radiance integrates to the irradiance I / d² (inverse-square law).
        out.p = l.position;
        out.n = Vec3f(0.f);
        Vec3f d = l.position - ref;
        float dist2 = glm::dot(d, d);
        if (!(dist2 > 0.f)) return false;
        out.Le = l.Le / dist2;
        out.pdfW = pmf_[index];
        out.isDelta = true;
        return true;
    }
    float pdfW = sampleOne(index, ref, u, out);
    if (!(pdfW > 0.f) || !std::isfinite(pdfW)) return false;
    out.pdfW = pdfW * pmf_[index];
    out.isDelta = false;
    out.Le = emitted(index, out.n, glm::normalize(ref - out.p));
    return true;
}

bool LightSet::sampleEmission(float uPick, Vec2f uPos, Vec2f uDir, LightEmission& out) const {
    if (lights_.empty()) return false;
    uint32_t index = pick(uPick);
    if (index == kInvalidId) return false;
    const Light& l = lights_[index];
    out.index = index;
    if (l.type == LightType::Point) {
        out.p = l.position;
        out.n = Vec3f(0.f);
        out.dir = sampleUniformSphere(uDir);
        out.Le = l.Le;
        out.pdfPosA = pmf_[index];
        out.pdfDirW = kUniformSpherePdfW;
        out.isDeltaPos = true;
        return true;
    }
    if (l.type == LightType::Triangle) {
        samplePointOnTriangle(geometry_->meshes[l.geomId], l.primId, uPos, out.p, out.n);
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
    out.Le = l.Le;
    out.isDeltaPos = false;
    pdfEmission(index, out.n, out.dir, out.pdfPosA, out.pdfDirW);
    return out.pdfPosA > 0.f && out.pdfDirW > 0.f;
}

void LightSet::pdfEmission(uint32_t index, const Vec3f& n, const Vec3f& dir, float& pdfPosA, float& pdfDirW) const {
    const Light& l = lights_[index];
    if (l.type == LightType::Point) {
        pdfPosA = pmf_[index];
        pdfDirW = kUniformSpherePdfW;
        return;
    }
    pdfPosA = l.area > 0.f ? pmf_[index] / l.area : 0.f;
    float c = glm::dot(n, dir);
    if (l.twoSided) pdfDirW = 0.5f * std::abs(c) * kInvPi;
    else pdfDirW = c > 0.f ? c * kInvPi : 0.f;
}

float LightSet::pdfW(uint32_t index, const Vec3f& ref, const Vec3f& pLight, const Vec3f& nLight) const {
    return pmf_[index] * pdfOneW(index, ref, pLight, nLight);
}

float LightSet::sampleOne(uint32_t index, const Vec3f& ref, Vec2f u, LightSample& out) const {
    const Light& l = lights_[index];
    if (l.type == LightType::Triangle) {
        samplePointOnTriangle(geometry_->meshes[l.geomId], l.primId, u, out.p, out.n);
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
    if (l.type == LightType::Point) return 0.f;  // a delta light is never hit by a ray
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
