#include "scene/gltf_files.h"

#include <fstream>

namespace tessera {
namespace {

std::string canonicalPath(const std::string& path) {
    std::error_code ec;
    std::filesystem::path c = std::filesystem::weakly_canonical(path, ec);
    return ec ? path : c.string();
}

bool fsFileExists(const std::string& path, void*) {
    // Existence is not access: the read below refuses files outside the folder and says why.
    std::error_code ec;
    return std::filesystem::is_regular_file(path, ec);
}

std::string fsExpandFilePath(const std::string& path, void*) { return path; }

bool fsReadWholeFile(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
    auto* fa = static_cast<GltfFileAccess*>(user);
    if (!fa->allowed(path)) {
        if (err) *err += "refused to read " + path + "\n";
        return false;
    }
    std::error_code ec;
    uint64_t size = std::filesystem::file_size(path, ec);
    if (ec) {
        if (err) *err += "cannot read " + path + "\n";
        return false;
    }
    if (size > fa->options.maxFileBytes) {
        fa->refuse(path, "'" + path + "' is " + std::to_string(size) + " bytes, over the limit of " +
                             std::to_string(fa->options.maxFileBytes));
        if (err) *err += "file too large: " + path + "\n";
        return false;
    }
    std::ifstream in(path, std::ios::binary);
    out->resize(size_t(size));
    if (size > 0 && !in.read(reinterpret_cast<char*>(out->data()), std::streamsize(size))) {
        if (err) *err += "cannot read " + path + "\n";
        return false;
    }
    return true;
}

bool fsWriteWholeFile(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    if (err) *err += "writing is not allowed while loading\n";
    return false;
}

}  // namespace

tinygltf::FsCallbacks GltfFileAccess::callbacks() {
    return tinygltf::FsCallbacks{fsFileExists, fsExpandFilePath, fsReadWholeFile, fsWriteWholeFile, this};
}

void GltfFileAccess::refuse(const std::string& path, const std::string& why) {
    if (violation.empty()) violation = why;
    refusals.emplace(canonicalPath(path), why);
}

std::string GltfFileAccess::whyRefused(const std::string& path) const {
    auto it = refusals.find(canonicalPath(path));
    return it == refusals.end() ? std::string() : it->second;
}

bool GltfFileAccess::allowed(const std::string& path) {
    std::error_code ec;
    std::filesystem::path canonical = std::filesystem::weakly_canonical(path, ec);
    if (ec) return false;
    if (options.allowExternalFiles) return true;
    auto rel = canonical.lexically_relative(root);
    bool inside = !rel.empty() && rel.native().rfind("..", 0) != 0 && !rel.is_absolute();
    if (!inside) refuse(path, "'" + path + "' lies outside the scene's folder (pass --allow-external-files to permit it)");
    return inside;
}

}  // namespace tessera
