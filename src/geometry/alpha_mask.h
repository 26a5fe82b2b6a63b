#pragma once
/// \file alpha_mask.h
/// Cut-out geometry (glTF alphaMode MASK, and BLEND rendered as MASK): a hit on a masked triangle
/// counts only where alpha = factor × baseColorTexture.a ≥ cutoff. Every backend (our BVH and k-d
/// tree, Embree's filter functions) calls the one test below, so they agree hit for hit.
#include "texture/texture.h"

namespace tessera {

struct TriangleMesh;

struct AlphaMask {
    TextureRef texture;  ///< the base-colour texture (its alpha channel), or unset
    float factor = 1.f;  ///< baseColorFactor.a
    float cutoff = 0.5f;
};

/// True when the hit at barycentrics (u, v) of triangle `primId` of `mesh` is kept. The lookup uses
/// the finest MIP level so that the answer does not depend on the ray.
bool alphaMaskKeeps(const TriangleMesh& mesh, uint32_t primId, float u, float v);

}  // namespace tessera
