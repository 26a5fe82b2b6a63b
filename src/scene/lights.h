#pragma once
/// \file lights.h
/// Emitters: every triangle or sphere whose material emits is one light. Lights are chosen in
/// proportion to their power; a light sampled from a reference point returns a point on it with the
/// solid-angle density of choosing it (selection probability included).
#include <vector>

#include "core/math.h"
#include "geometry/shapes.h"
#include "materials/material.h"

namespace tessera {

enum class LightType { Triangle, Sphere };

struct Light {
    LightType type = LightType::Triangle;
    uint32_t geomId = kInvalidId;  ///< for spheres: the SceneGeometry sphere geometry id
    uint32_t primId = kInvalidId;  ///< triangle index in the mesh, or sphere index
    Rgb Le{0.f};
    bool twoSided = false;
    float area = 0.f;
};

struct LightSample {
    Vec3f p{0.f};     ///< point on the light
    Vec3f n{0.f};     ///< unit surface normal at p (outward / front face)
    Rgb Le{0.f};      ///< radiance leaving p towards the reference point (0 if p shows its back)
    float pdfW = 0.f; ///< solid-angle density at the reference point, light selection included
};

class LightSet {
public:
    /// Collects the emitters of `geometry` with materials `materials`. Lights of zero area are skipped.
    void build(const SceneGeometry& geometry, const std::vector<Material>& materials);

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

    /// Selection probability of light `index`.
    float pickPmf(uint32_t index) const { return pmf_[index]; }

private:
    float sampleOne(uint32_t index, const Vec3f& ref, Vec2f u, LightSample& out) const;
    float pdfOneW(uint32_t index, const Vec3f& ref, const Vec3f& pLight, const Vec3f& nLight) const;

    const SceneGeometry* geometry_ = nullptr;
    std::vector<Light> lights_;
    std::vector<float> pmf_, cdf_;
    std::vector<uint32_t> meshFirstLight_;   ///< per mesh: index of its first triangle light, or invalid
    std::vector<uint32_t> sphereLight_;      ///< per sphere: its light index, or invalid
};

}  // namespace tessera
