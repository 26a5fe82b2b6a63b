/// \file alpha_mask.cpp
/// The one alpha test of cut-out geometry (glTF alphaMode MASK). Every backend calls it with the
/// barycentrics of its own triangle test: ours with the watertight test's (bit-identical across the
/// BVH, SBVH, k-d tree and brute force), Embree's filter with the same test recomputed
/// (embree_accel.cpp), so that all of them keep or drop exactly the same hits.
#include "geometry/alpha_mask.h"

#include <cmath>

#include "geometry/shapes.h"

namespace tessera {

bool alphaMaskKeeps(const TriangleMesh& mesh, uint32_t primId, float u, float v) {
    const AlphaMask* mask = mesh.alphaMask.get();
    if (!mask) return true;
    // glTF 2.0, "Alpha Coverage": alpha = baseColorFactor.a × baseColorTexture.a; MASK keeps the
    // fragment when alpha ≥ alphaCutoff (equal counts as opaque).
    float alpha = mask->factor;
    if (mask->texture.valid()) {
        int set = mask->texture.texCoord;
        // A set the mesh lacks reads as (0, 0), as texcoordAt does for a missing attribute; the
        // loader rejects sets beyond TEXCOORD_1, this only keeps the index in range.
        Vec2f uv = set < 2 ? mesh.texcoordAt(set, primId, u, v) : Vec2f(0.f);
        // Non-finite coordinates (a NaN in the file's TEXCOORD data) have no texel: dropped, as a
        // NaN alpha would be, never looked up.
        if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return false;
        // Footprint 0: the finest MIP level, so that the answer depends on the hit point only and
        // never on the ray's footprint (camera and shadow rays through a fence must agree).
        alpha *= sampleTexture(mask->texture, uv, /*footprintUv=*/0.f).a;
    }
    // A NaN alpha fails the comparison: the hit is dropped, never kept at random.
    return alpha >= mask->cutoff;
}

}  // namespace tessera
