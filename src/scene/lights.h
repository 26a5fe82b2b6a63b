#pragma once
/// \file lights.h
/// Emitters: every triangle or sphere whose material emits is one light, every KHR_lights_punctual
/// light (point, spot, directional) and the environment (scene/environment.h). Lights are chosen in
/// proportion to their power (the infinite lights' power uses the scene's bounding sphere, as pbrt-v4
/// does: Φ = π r² ∫ L dω for the environment, π r² E for a directional light). Each light can
///  * be sampled from a reference point (next-event estimation, BDPT's s = 1): a point on it with
///    the solid-angle density at the reference point, selection probability included;
///  * emit (light tracing, BDPT's light sub-paths): a position with pdfPosA and a direction with
///    pdfDirW (Veach 1997, §10.2: the light sub-path's first two vertices).
/// Point and spot lights are deltas in position: they cannot be hit by rays, their "radiance" towards
/// a point is the radiant intensity I / d², and their pdfPosA is the (discrete) selection probability.
/// Infinite lights (environment, directional) lie "at infinity": a sample is a direction, and their
/// light sub-paths start on a disk of the scene's bounding radius r perpendicular to the direction,
/// with the planar density 1/(π r²) (pbrt-v4 §12.5, Veach 1997 §10.2). A directional light is a delta
/// in direction: it can be neither hit nor sampled by a BSDF.
#include <vector>

#include "core/distribution.h"
#include "core/math.h"
#include "geometry/shapes.h"
#include "materials/material.h"
#include "scene/environment.h"

namespace tessera {

enum class LightType { Triangle, Sphere, Point, Spot, Directional, Environment };

struct Light {
    LightType type = LightType::Triangle;
    uint32_t geomId = kInvalidId;  ///< for spheres: the SceneGeometry sphere geometry id
    uint32_t primId = kInvalidId;  ///< triangle index in the mesh, or sphere index
    Rgb Le{0.f};          ///< emitted radiance (area lights), radiant intensity in W/sr (point, spot: on the
                          ///< axis) or irradiance in W/m² (directional); unused for the environment
    bool twoSided = false;
    float area = 0.f;     ///< 0 for all but area lights
    Vec3f position{0.f};  ///< point and spot lights
    Vec3f direction{0.f}; ///< spot: unit cone axis (direction of emission); directional: unit direction of travel
    float cosInner = 1.f, cosOuter = -1.f;  ///< spot cone: full intensity inside inner, none outside outer
};

/// A point light as the scene loader describes it (KHR_lights_punctual, type "point").
struct PointLightDesc {
    Vec3f position{0.f};
    Rgb intensity{0.f};  ///< radiant intensity (W/sr per RGB channel)
};

/// KHR_lights_punctual "spot": a point light restricted to a cone about `direction` with the
/// extension's smooth falloff between the inner and outer cone angles (spotFalloff below).
struct SpotLightDesc {
    Vec3f position{0.f};
    Vec3f direction{0.f, 0.f, -1.f};  ///< unit; the node's local −Z
    Rgb intensity{0.f};               ///< on the axis, W/sr
    float innerConeAngle = 0.f;       ///< radians, 0 ≤ inner < outer ≤ π/2
    float outerConeAngle = 0.25f * kPi;
};

/// KHR_lights_punctual "directional": parallel light travelling along `direction` (the node's −Z).
struct DirectionalLightDesc {
    Vec3f direction{0.f, 0.f, -1.f};  ///< unit direction the light travels
    Rgb irradiance{0.f};              ///< W/m² on a surface facing the light (glTF lux, 1:1)
};

/// The KHR_lights_punctual spot falloff (the extension's reference implementation): with
/// t = (cos θ − cos outer) / (cos inner − cos outer) clamped to [0, 1], the intensity is scaled by t².
inline float spotFalloff(float cosTheta, float cosInner, float cosOuter) {
    if (cosTheta <= cosOuter) return 0.f;
    if (cosTheta >= cosInner) return 1.f;
    float t = (cosTheta - cosOuter) / std::max(cosInner - cosOuter, 1e-6f);
    return t * t;
}

struct LightSample {
    Vec3f p{0.f};     ///< point on the light (infinite lights: a point 2r beyond the reference point along wi)
    Vec3f n{0.f};     ///< unit surface normal at p (outward / front face); zero for point, spot and infinite lights
    Vec3f wi{0.f};    ///< unit direction from the reference point towards the light
    Vec2f bary{0.f};  ///< triangle lights: the point's barycentrics (u, v) of vertices 1 and 2, as in Hit
    Rgb Le{0.f};      ///< radiance leaving p towards the reference point (0 if p shows its back);
                      ///< for a point or spot light the intensity divided by d², i.e. the irradiance at
                      ///< normal incidence; for a directional light its irradiance
    float pdfW = 0.f; ///< solid-angle density at the reference point, light selection included;
                      ///< for a delta light (isDelta) the discrete selection probability
    bool isDelta = false;     ///< point, spot, directional: BSDF sampling cannot find it
    bool isInfinite = false;  ///< environment, directional: no end point, the shadow ray is unbounded
    uint32_t index = kInvalidId;  ///< the light sampled
};

/// A ray leaving a light, for light sub-paths.
/// Infinite lights swap the roles of the two densities (pbrt-v3 §16.3.1): the direction is chosen
/// first (pdfDirW, selection included; a directional light's is its selection probability) and the
/// origin on the disk of radius r perpendicular to it, pdfPosA = 1/(π r²) (planar, no selection).
struct LightEmission {
    Vec3f p{0.f};
    Vec3f n{0.f};          ///< unit normal at p (front face); zero for point, spot and infinite lights
    Vec3f dir{0.f};        ///< unit direction of emission
    Rgb Le{0.f};           ///< radiance (area, environment), intensity (point, spot) or irradiance (directional) along dir
    float pdfPosA = 0.f;   ///< area density of p, selection included (point, spot: selection probability)
    float pdfDirW = 0.f;   ///< solid-angle density of dir given p
    bool isDeltaPos = false;
    bool isInfinite = false;
    Vec2f bary{0.f};       ///< triangle lights: the point's barycentrics (u, v) of vertices 1 and 2
    uint32_t index = kInvalidId;
};

class LightSet {
public:
    /// Collects the emitters of `geometry` with materials `materials`, the punctual lights and the
    /// environment. Lights of zero area or zero power get selection probability 0.
    void build(const SceneGeometry& geometry, const std::vector<Material>& materials,
               const std::vector<PointLightDesc>& pointLights = {}, const std::vector<SpotLightDesc>& spotLights = {},
               const std::vector<DirectionalLightDesc>& directionalLights = {}, const EnvironmentDesc* environment = nullptr);

    /// Points the set at `geometry`, a moved copy of the geometry it was built from.
    void rebind(const SceneGeometry& geometry) { geometry_ = &geometry; }

    bool empty() const { return lights_.empty(); }
    size_t size() const { return lights_.size(); }
    const Light& light(uint32_t i) const { return lights_[i]; }

    /// Light index of primitive (geomId, primId), or kInvalidId when it does not emit.
    uint32_t lightIndexOf(uint32_t geomId, uint32_t primId) const;

    /// Picks a light ∝ power with `uPick` and samples a point on it seen from `ref`.
    bool sample(const Vec3f& ref, float uPick, Vec2f u, LightSample& out) const;
    /// Density (solid angle at `ref`, selection included) with which sample() produces the point
    /// `pLight` (normal `nLight`) on light `index`: the MIS counterpart of a BSDF-sampled hit.
    float pdfW(uint32_t index, const Vec3f& ref, const Vec3f& pLight, const Vec3f& nLight) const;
    /// Radiance leaving light `index` at a point with normal `n` in direction `w` (unit); `bary`
    /// (the point's barycentrics on a triangle light, as in Hit) places it on an emissive texture.
    /// For point and spot lights the intensity towards w, for a directional light its irradiance,
    /// for the environment the radiance arriving from −w.
    Rgb emitted(uint32_t index, const Vec3f& n, const Vec3f& w, Vec2f bary) const;
    /// The radiance of area light `index` at barycentrics `bary`: the material's emission times its
    /// emissive texture there (glTF emissiveFactor × emissiveTexture), ignoring the facing.
    Rgb radianceAt(uint32_t index, Vec2f bary) const;

    /// The environment, if any: its light index, the radiance arriving from direction `wLight` (unit,
    /// pointing away from the scene; 0 without an environment) and the solid-angle density, light
    /// selection included, with which sample() picks that direction.
    bool hasEnvironment() const { return environmentIndex_ != kInvalidId; }
    uint32_t environmentIndex() const { return environmentIndex_; }
    Rgb environmentLe(const Vec3f& wLight) const { return hasEnvironment() ? environment_.Le(wLight) : Rgb(0.f); }
    float environmentPdfW(const Vec3f& wLight) const;
    const EnvironmentLight& environment() const { return environment_; }

    /// Picks a light ∝ power and samples an emitted ray: position ∝ area (uniform), direction
    /// cosine-weighted about the emitting face (either face with probability ½ when two-sided),
    /// uniform over the sphere for point lights.
    bool sampleEmission(float uPick, Vec2f uPos, Vec2f uDir, LightEmission& out) const;
    /// The densities sampleEmission would have had for emitting from p (normal n) in direction
    /// `dir` on light `index`: pdfPosA (selection included) and pdfDirW.
    void pdfEmission(uint32_t index, const Vec3f& n, const Vec3f& dir, float& pdfPosA, float& pdfDirW) const;
    /// True for lights that are a delta in position (point and spot lights).
    bool isDeltaPosition(uint32_t index) const {
        return lights_[index].type == LightType::Point || lights_[index].type == LightType::Spot;
    }
    /// True for lights no ray can hit: deltas in position or in direction (directional lights).
    bool isDelta(uint32_t index) const { return isDeltaPosition(index) || lights_[index].type == LightType::Directional; }
    /// True for lights at infinity (environment, directional).
    bool isInfinite(uint32_t index) const {
        return lights_[index].type == LightType::Environment || lights_[index].type == LightType::Directional;
    }
    /// The bounding sphere the infinite lights' emission disk covers, and its planar density 1/(π r²).
    Vec3f sceneCenter() const { return sceneCenter_; }
    float sceneRadius() const { return sceneRadius_; }
    float diskPdfA() const { return 1.f / (kPi * sceneRadius_ * sceneRadius_); }

    /// Selection probability of light `index`.
    float pickPmf(uint32_t index) const { return selection_.pmf(index); }

private:
    uint32_t pick(float uPick) const;
    Rgb intensityTowards(const Light& l, const Vec3f& w) const;
    bool sampleInfiniteEmission(uint32_t index, Vec2f uPos, Vec2f uDir, LightEmission& out) const;
    float sampleOne(uint32_t index, const Vec3f& ref, Vec2f u, LightSample& out) const;
    float pdfOneW(uint32_t index, const Vec3f& ref, const Vec3f& pLight, const Vec3f& nLight) const;

    const SceneGeometry* geometry_ = nullptr;
    std::vector<Light> lights_;
    Distribution1D selection_;               ///< light selection ∝ power
    EnvironmentLight environment_;
    uint32_t environmentIndex_ = kInvalidId;
    Vec3f sceneCenter_{0.f};
    float sceneRadius_ = 1.f;
    std::vector<uint32_t> meshFirstLight_;   ///< per mesh: index of its first triangle light, or invalid
    std::vector<uint32_t> sphereLight_;      ///< per sphere: its light index, or invalid
    std::vector<TextureRef> meshEmissive_;   ///< per mesh: its material's emissive texture (invalid: none)
};

}  // namespace tessera
