#pragma once
/// \file ray_sets.h
/// Reproducible ray sets over a scene's geometry: the rays `tessera validate-accel` compares
/// structure against structure, and the rays `tessera bench-accel` times them on. One generator for
/// both, so a benchmark's rays are rays the validator has checked.
#include <optional>
#include <string_view>
#include <vector>

#include "accel/accel.h"
#include "scene/camera.h"

namespace tessera {

enum class RayKind {
    Primary,  ///< a pinhole camera through jittered pixels, in pixel order (the scene's camera or one framing the bounds)
    Random,   ///< origins around the bounds, uniform or aimed directions, some axis-aligned with ±0.0, some tMin > 0
    Diffuse,  ///< cosine-distributed bounces from the reference's primary hits (offset origins), in random order
    Grazing,  ///< aimed at triangle edges and vertices and at sphere silhouettes, often nearly tangent
    Shadow,   ///< from the reference's primary hits to random points on the top face of the bounds (any-hit queries)
};
std::string_view toString(RayKind kind);
/// Parses "primary", "random", "diffuse", "grazing", "shadow"; throws InputError otherwise.
RayKind parseRayKind(std::string_view name);
/// The kinds `validate-accel --kind all` casts (shadow rays are the benchmark's any-hit set).
inline constexpr RayKind kValidationRayKinds[] = {RayKind::Primary, RayKind::Random, RayKind::Diffuse, RayKind::Grazing};

/// `count` rays of one kind, reproducible from `seed`. Diffuse and shadow rays need the reference
/// structure (to find the surfaces they start from) and are topped up with random rays when the
/// camera sees too little; `camera` is used by primary, diffuse and shadow rays when given.
std::vector<Ray> generateRays(const SceneGeometry& geometry, const Accel& reference, RayKind kind, size_t count,
                              uint64_t seed, const std::optional<CameraDesc>& camera = std::nullopt);

/// A camera looking at the centre of `bounds` from a fixed oblique direction, framing all of it.
CameraDesc framingCamera(const Bounds3f& bounds);

}  // namespace tessera
