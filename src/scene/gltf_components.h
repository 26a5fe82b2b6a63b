#pragma once
/// \file gltf_components.h
/// Accessor components of the glTF loader (internal to scene/): integer and float components as
/// floats, with glTF's normalisation (KHR_mesh_quantization's integer attributes included).

namespace tessera {

/// One integer accessor component (unaligned bytes, little endian) as a float. Normalized integers
/// map as glTF 2.0 §3.11 defines: f = max(c / 127, −1), c / 255, max(c / 32767, −1), c / 65535.
float componentAsFloat(const unsigned char* p, int componentType, bool normalized);

}  // namespace tessera
