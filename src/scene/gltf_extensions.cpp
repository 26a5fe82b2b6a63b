#include "scene/gltf_extensions.h"

#include <utility>
#include <vector>

namespace tessera {

ExtensionEffect unsupportedExtensionEffect(const std::string& name) {
    static const char* const kDecompress = "write the file without mesh compression first (Tessera reads uncompressed geometry only)";
    static const std::vector<std::pair<std::string, ExtensionEffect>> kKnown = {
        {"KHR_draco_mesh_compression", {"its Draco-compressed copies of primitives are ignored (their uncompressed accessors are used)", kDecompress}},
        {"EXT_meshopt_compression", {"its compressed buffer views are ignored (their fallback buffers are used)", kDecompress}},
        {"KHR_materials_clearcoat", {"the clearcoat layer is not rendered", ""}},
        {"KHR_materials_sheen", {"the sheen layer is not rendered", ""}},
        {"KHR_materials_iridescence", {"thin-film iridescence is not rendered", ""}},
        {"KHR_materials_anisotropy", {"anisotropy is ignored (roughness is isotropic)", ""}},
        {"KHR_materials_dispersion", {"dispersion is ignored (one IOR for all wavelengths)", ""}},
        {"KHR_materials_diffuse_transmission", {"diffuse transmission is ignored (such surfaces are opaque)", ""}},
        {"KHR_materials_unlit", {"unlit materials are shaded as lit metallic-roughness materials", ""}},
        {"KHR_materials_variants", {"material variants are ignored (each primitive's default material is used)", ""}},
        {"KHR_materials_pbrSpecularGlossiness", {"specular-glossiness parameters are ignored (the metallic-roughness ones are used)", ""}},
        {"KHR_texture_basisu", {"KTX2 textures are ignored (the fallback PNG/JPEG source, if any, is used)", ""}},
        {"EXT_texture_webp", {"WebP textures are ignored (the fallback PNG/JPEG source, if any, is used)", ""}},
        {"EXT_texture_avif", {"AVIF textures are ignored (the fallback PNG/JPEG source, if any, is used)", ""}},
        {"EXT_mesh_gpu_instancing", {"instancing is ignored (each mesh is rendered once, at its node)", ""}},
        {"KHR_animation_pointer", {"animations are ignored", ""}},
        {"KHR_xmp_json_ld", {"XMP metadata is ignored", ""}},
        {"EXT_lights_image_based", {"image-based lights are ignored", ""}},
    };
    for (const auto& [known, effect] : kKnown)
        if (known == name) return effect;
    return {"its data is ignored", ""};
}

}  // namespace tessera
