#pragma once
/// \file validate.h
/// Ray-by-ray comparison of an acceleration structure against a reference (normally Embree): the
/// library side of `tessera validate-accel` and of the BVH tests. Every disagreement is classified
/// as a *tie* (both answers are admissible: a shared edge or vertex, coplanar duplicates, a ray
/// grazing an edge or a sphere's silhouette — confirmed in double precision) or an *error*.
#include <nlohmann/json.hpp>

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "accel/accel.h"
#include "scene/camera.h"

namespace tessera {

enum class RayKind {
    Primary,  ///< a pinhole camera through jittered pixels (the scene's camera or one framing the bounds)
    Random,   ///< origins around the bounds, uniform or aimed directions, some axis-aligned with ±0.0, some tMin > 0
    Diffuse,  ///< cosine-distributed bounces from the reference's primary hits (offset origins)
    Grazing,  ///< aimed at triangle edges and vertices and at sphere silhouettes, often nearly tangent
};
std::string_view toString(RayKind kind);
/// Parses "primary", "random", "diffuse", "grazing"; throws InputError otherwise.
RayKind parseRayKind(std::string_view name);
inline constexpr RayKind kAllRayKinds[] = {RayKind::Primary, RayKind::Random, RayKind::Diffuse, RayKind::Grazing};

/// `count` rays of one kind, reproducible from `seed`. Diffuse rays need the reference structure
/// (to find the surfaces they bounce from); `camera` is used by primary and diffuse rays when given.
std::vector<Ray> generateRays(const SceneGeometry& geometry, const Accel& reference, RayKind kind, size_t count,
                              uint64_t seed, const std::optional<CameraDesc>& camera = std::nullopt);

/// A camera looking at the centre of `bounds` from a fixed oblique direction, framing all of it.
CameraDesc framingCamera(const Bounds3f& bounds);

struct ValidationTolerances {
    float tRelative = 1e-5f;  ///< |Δt| ≤ tRelative·t (plus a few ulps of the origin's magnitude)
    float uv = 1e-4f;         ///< |Δu|, |Δv| on the same triangle
    float normalCos = 0.9999f;  ///< dot(ng_test, ng_ref) at least this
    /// Float precision in ulps of the coordinates' magnitude: how far from an edge (or a sphere's
    /// silhouette) a ray may pass and still be called a tie when the two answers differ.
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
