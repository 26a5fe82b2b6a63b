#pragma once
/// \file material.h
/// The four materials the scenes need and no more: Lambertian, perfect mirror, smooth dielectric,
/// GGX rough conductor. A material is a plain tagged struct: BSDF calls run once per bounce, so they
/// dispatch with a switch, not a virtual call (as pbrt-v4 dispatches its per-bounce types).
#include <string>

#include "core/math.h"

namespace tessera {

enum class MaterialType { Diffuse, Mirror, Dielectric, RoughConductor };

struct Material {
    std::string name;
    MaterialType type = MaterialType::Diffuse;
    Rgb albedo{0.8f};     ///< diffuse albedo; F0 of conductors (Schlick); transmission tint of dielectrics
    float ior = 1.5f;     ///< dielectric index of refraction (outside medium: vacuum)
    float alpha = 0.f;    ///< GGX roughness α = glTF roughness² (Burley 2012 remapping)
    Rgb emission{0.f};    ///< emitted radiance; non-zero makes every triangle/sphere of it a light
    bool doubleSided = false;  ///< emission from both faces (glTF doubleSided); BSDFs are always two-sided

    bool isEmissive() const { return !isBlack(emission); }
};

/// Direction of transport along a path: radiance (camera sub-paths) or importance (light sub-paths).
/// Refraction scales radiance by 1/η², but not importance (Veach 1997, Section 5.2).
enum class TransportMode { Radiance, Importance };

}  // namespace tessera
