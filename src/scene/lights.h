#pragma once
/// \file lights.h
/// Emitters: every triangle or sphere whose material emits is one light, and every point light
/// (glTF KHR_lights_punctual "point"). Lights are chosen in proportion to their power. Each light can
///  * be sampled from a reference point (next-event estimation, BDPT's s = 1): a point on it with
///    the solid-angle density at the reference point, selection probability included;
///  * emit (light tracing, BDPT's light sub-paths): a position with pdfPosA and a direction with
///    pdfDirW (Veach 1997, §10.2: the light sub-path's first two vertices).
/// A point light is a delta in position: it cannot be hit by rays, its "radiance" towards a point is
/// the radiant intensity I / d², and its pdfPosA is the (discrete) selection probability.
#include <vector>

#include "core/math.h"
#include "geometry/shapes.h"
#include "materials/material.h"

namespace tessera {

enum class LightType { Triangle, Sphere, Point };

struct Light {
    LightType type = LightType::Triangle;
    uint32_t geomId = kInvalidId;  ///< for spheres: the SceneGeometry sphere geometry id
    uint32_t primId = kInvalidId;  ///< triangle index in the mesh, or sphere index
    Rgb Le{0.f};          ///< emitted radiance (area lights) or radiant intensity in W/sr (point lights)
    bool twoSided = false;
    float area = 0.f;     ///< 0 for point lights
    Vec3f position{0.f};  ///< point lights only
};

/// A point light as the scene loader describes it (KHR_lights_punctual, type "point").
struct PointLightDesc {
    Vec3f position{0.f};
    Rgb intensity{0.f};  ///< radiant intensity (W/sr per RGB channel)
};

struct LightSample {
    Vec3f p{0.f};     ///< point on the light
    Vec3f n{0.f};     ///< unit surface normal at p (outward / front face); zero for point lights
    Rgb Le{0.f};      ///< radiance leaving p towards the reference point (0 if p shows its back);
                      ///< for a point light the intensity divided by d², i.e. the irradiance at normal incidence
    float pdfW = 0.f; ///< solid-angle density at the reference point, light selection included;
                      ///< for a point light (isDelta) the discrete selection probability
    bool isDelta = false;
    uint32_t index = kInvalidId;  ///< the light sampled
};

/// A ray leaving a light, for light sub-paths.
struct LightEmission {
    Vec3f p{0.f};
    Vec3f n{0.f};          ///< unit normal at p (front face); zero for point lights
    Vec3f dir{0.f};        ///< unit direction of emission
    Rgb Le{0.f};           ///< radiance (area lights) or intensity (point lights) along dir
    float pdfPosA = 0.f;   ///< area density of p, selection included (point: selection probability)
    float pdfDirW = 0.f;   ///< solid-angle density of dir given p
    bool isDeltaPos = false;
    uint32_t index = kInvalidId;
};

class LightSet {
public:
    /// Collects the emitters of `geometry` with materials `materials`. Lights of zero area are skipped.
    void build(const SceneGeometry& geometry, const std::vector<Material>& materials,
               const std::vector<PointLightDesc>& pointLights = {});

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
    /// Radiance leaving light `index` at a point with normal `n` in direction `w` (unit).
    Rgb emitted(uint32_t index, const Vec3f& n, const Vec3f& w) const;

    /// Picks a light ∝ power and samples an emitted ray: position ∝ area (uniform), direction
    /// cosine-weighted about the emitting face (either face with probability ½ when two-sided),
    /// uniform over the sphere for point lights.
    bool sampleEmission(float uPick, Vec2f uPos, Vec2f uDir, LightEmission& out) const;
    /// The densities sampleEmission would have had for emitting from p (normal n) in direction
    /// `dir` on light `index`: pdfPosA (selection included) and pdfDirW.
    void pdfEmission(uint32_t index, const Vec3f& n, const Vec3f& dir, float& pdfPosA, float& pdfDirW) const;
    /// True for lights that are a delta in position (point lights).
    bool isDeltaPosition(uint32_t index) const { return lights_[index].type == LightType::Point; }

    /// Selection probability of light `index`.
    float pickPmf(uint32_t index) const { return pmf_[index]; }

private:
    uint32_t pick(float uPick) const;
    float sampleOne(uint32_t index, const Vec3f& ref, Vec2f u, LightSample& out) const;
    float pdfOneW(uint32_t index, const Vec3f& ref, const Vec3f& pLight, const Vec3f& nLight) const;

    const SceneGeometry* geometry_ = nullptr;
    std::vector<Light> lights_;
    std::vector<float> pmf_, cdf_;
    std::vector<uint32_t> meshFirstLight_;   ///< per mesh: index of its first triangle light, or invalid
    std::vector<uint32_t> sphereLight_;      ///< per sphere: its light index, or invalid
};

}  // namespace tessera
