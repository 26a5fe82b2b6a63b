#pragma once
/// \file validate.h
/// Ray-by-ray comparison of an acceleration structure against a reference (normally Embree): the
/// library side of `tessera validate-accel` and of the BVH tests. Every disagreement is classified
/// as a *tie* (both answers are admissible: a shared edge or vertex, coplanar duplicates, a ray
/// grazing an edge or a sphere's silhouette — confirmed in double precision) or an *error*.
#include <nlohmann/json.hpp>

#include <span>
#include <string>
#include <vector>

#include "accel/accel.h"
#include "validation/ray_sets.h"

namespace tessera {

struct ValidationTolerances {
    float tRelative = 1e-5f;  ///< |Δt| ≤ tRelative·t (plus a few ulps of the origin's magnitude)
    float uv = 1e-4f;         ///< |Δu|, |Δv| on the same triangle
    float normalCos = 0.9999f;  ///< dot(ng_test, ng_ref) at least this
    /// Float precision in ulps of the coordinates' magnitude: how far rounding may move a triangle's
    /// edges or a sphere's surface (a triangle's plane: times its condition number), so how far from
    /// an edge or silhouette a ray may pass and still be called a tie when the two answers differ.
    float edgeUlps = 64.f;
};

struct ValidationExample {
    RayKind kind;
    size_t rayIndex;
    Ray ray;
    bool testHit, refHit;
    Hit test, ref;
    std::string reason;
};

struct ValidationResult {
    size_t rays = 0, agreements = 0, ties = 0, errors = 0;
    std::vector<ValidationExample> examples;  ///< the first errors, in ray order
    void merge(const ValidationResult& other, size_t maxExamples);
};

/// Casts every ray through both structures (closest hit, and any hit for the tested one, which must
/// agree with its own closest hit) and classifies each ray. Parallel over rays; deterministic.
ValidationResult compareAccels(const Accel& test, const Accel& reference, const SceneGeometry& geometry,
                               std::span<const Ray> rays, RayKind kind, const ValidationTolerances& tol = {},
                               size_t maxExamples = 20);

nlohmann::json toJson(const ValidationResult& result);
nlohmann::json toJson(const Ray& ray);
nlohmann::json toJson(const Hit& hit, bool found);

}  // namespace tessera
