#include "scene/assets.h"

#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace tessera {

namespace fs = std::filesystem;

std::vector<std::string> defaultAssetRoots() {
    std::vector<std::string> roots;
    if (const char* env = std::getenv("TESSERA_ASSETS")) {
        std::stringstream ss(env);
        std::string item;
        while (std::getline(ss, item, ':'))
            if (!item.empty()) roots.push_back(item);
    }
    if (const char* cache = std::getenv("TESSERA_CACHE"); cache && *cache) roots.push_back(cache);
    else if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) roots.push_back(std::string(xdg) + "/tessera");
    else if (const char* home = std::getenv("HOME"); home && *home) roots.push_back(std::string(home) + "/.cache/tessera");
    return roots;
}

bool isValidAssetName(const std::string& name) {
    if (name.empty() || name.size() > 256) return false;
    std::stringstream ss(name);
    std::string part;
    size_t parts = 0;
    while (std::getline(ss, part, '/')) {
        ++parts;
        if (part.empty() || part == "." || part == "..") return false;
        for (char c : part)
            if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-')) return false;
    }
    return parts > 0 && name.back() != '/';
}

std::optional<std::string> resolveAsset(const std::string& name, const std::vector<std::string>& roots) {
    if (!isValidAssetName(name)) return std::nullopt;
    for (const std::string& root : roots) {
        std::error_code ec;
        fs::path canonicalRoot = fs::weakly_canonical(fs::absolute(root, ec), ec);
        if (ec || !fs::is_directory(canonicalRoot, ec)) continue;
        fs::path candidate = fs::path(root) / name;
        if (!fs::is_regular_file(candidate, ec)) continue;
        fs::path canonical = fs::weakly_canonical(candidate, ec);
        if (ec) continue;
        fs::path rel = canonical.lexically_relative(canonicalRoot);
        if (rel.empty() || rel.is_absolute() || rel.native().rfind("..", 0) == 0) continue;
        return candidate.string();
    }
    return std::nullopt;
}

}  // namespace tessera
