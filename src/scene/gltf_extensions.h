#pragma once
/// \file gltf_extensions.h
/// What the glTF loader does with an extension it does not implement. Policy (issue 16): one the
/// file requires is an error naming it (with `required` as the hint); one it only uses gives one
/// warning line naming it and saying what is ignored (`ignored`). The implemented extensions are
/// listed by supportedGltfExtensions() (scene/gltf_loader.h).
#include <string>

namespace tessera {

struct ExtensionEffect {
    std::string ignored;   ///< ends the warning when the extension is only used
    std::string required;  ///< ends the error when the file requires it ("" when there is nothing to add)
};

/// The effect of leaving out extension `name`; a generic one ("its data is ignored") for names
/// not in the table (KHR_draco_mesh_compression, EXT_meshopt_compression, KHR_materials_clearcoat, ...).
ExtensionEffect unsupportedExtensionEffect(const std::string& name);

}  // namespace tessera
