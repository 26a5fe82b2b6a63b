#pragma once
/// \file material.h
/// A material as the scene file gives it: the BSDF inputs (factors), emission, and the textures
/// that modulate them per surface point (texture/texture.h). BSDF calls run once per bounce, so
/// they dispatch with a switch on the BSDF type, not a virtual call (as pbrt-v4 dispatches its
/// per-bounce types).
#include <string>

#include "core/math.h"
#include "texture/texture.h"

namespace tessera {

/// Diffuse, Mirror, Dielectric and RoughConductor are the single-lobe special cases of Pbr, the
/// glTF 2.0 metallic-roughness material (materials/bsdf.h, finalizeBsdfParams).
enum class MaterialType { Diffuse, Mirror, Dielectric, RoughConductor, Pbr };

/// The BSDF inputs at one surface point: the material's factors, multiplied by its textures there.
/// Small and copied by value into SurfaceBsdf.
struct BsdfParams {
    MaterialType type = MaterialType::Diffuse;
    Rgb baseColor{0.8f};  ///< glTF baseColor: diffuse albedo; F0 of conductors (Schlick); transmission tint
    float metallic = 0.f;
    float alpha = 0.f;    ///< GGX roughness α = glTF roughness² (Burley 2012 remapping)
    float ior = 1.5f;     ///< dielectric index of refraction (outside medium: vacuum)
    float specular = 1.f;      ///< KHR_materials_specular specularFactor (× texture alpha)
    Rgb specularColor{1.f};    ///< KHR_materials_specular specularColorFactor (× texture)
    float transmission = 0.f;  ///< KHR_materials_transmission transmissionFactor (× texture R)
    bool thinWalled = true;    ///< KHR_materials_volume absent or thicknessFactor 0
    Rgb attenuationCoeff{0.f}; ///< Beer–Lambert σa per scene unit inside a volume (KHR_materials_volume)
    /// Derived by finalizeBsdfParams (MaterialType::Pbr): the cosine-weighted hemispherical average
    /// of the dielectric coat's reflectance, which normalizes the diffuse base's coupling.
    float coatFresnelAvg = 0.f;
};

enum class AlphaMode : uint8_t { Opaque, Mask, Blend };

/// The textures of a glTF material. An unset slot (no image) leaves its factor alone.
struct MaterialTextures {
    TextureRef baseColor;          ///< sRGB-decoded RGBA, multiplies baseColor and the alpha factor
    TextureRef metallicRoughness;  ///< linear; B = metallic, G = roughness
    TextureRef normal;             ///< tangent-space normal map (linear), with normalScale
    float normalScale = 1.f;
    TextureRef emissive;           ///< sRGB-decoded RGB, multiplies emission
    TextureRef transmission;       ///< linear; R multiplies transmission
    TextureRef specular;           ///< linear; A multiplies specular
    TextureRef specularColor;      ///< sRGB-decoded RGB, multiplies specularColor
    bool any() const {
        return baseColor.valid() || metallicRoughness.valid() || normal.valid() || emissive.valid() || transmission.valid() ||
               specular.valid() || specularColor.valid();
    }
};

struct Material {
    std::string name;
    BsdfParams bsdf;      ///< factors (and the BSDF type of an untextured point)
    Rgb emission{0.f};    ///< emitted radiance (× emissive texture); non-zero makes every triangle/sphere of it a light
    bool doubleSided = false;  ///< emission from both faces (glTF doubleSided); BSDFs are always two-sided
    float alphaFactor = 1.f;   ///< baseColorFactor.a
    AlphaMode alphaMode = AlphaMode::Opaque;
    float alphaCutoff = 0.5f;
    MaterialTextures textures;

    bool isEmissive() const { return !isBlack(emission); }
};

/// Direction of transport along a path: radiance (camera sub-paths) or importance (light sub-paths).
/// Refraction scales radiance by 1/η², but not importance (Veach 1997, Section 5.2).
enum class TransportMode { Radiance, Importance };

}  // namespace tessera
