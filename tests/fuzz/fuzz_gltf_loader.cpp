// libFuzzer target: any byte string given to the glTF loader must either load or throw an
// InputError, never crash, hang or leak (run under ASan+UBSan by tools/fuzz.sh). Inputs that start
// with the GLB magic are loaded as .glb, the rest as .gltf. Image decoding of untrusted bytes is
// reached three ways: images embedded in GLB buffer views and data URIs (seeds in tests/fuzz/seeds),
// and the image files written next to the scene (a valid PNG, a truncated one, a JPEG header).
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.h"
#include "scene/gltf_loader.h"

namespace {
std::string scenePath() {
    static const std::string path = [] {
        auto dir = std::filesystem::temp_directory_path() / ("tessera-fuzz-" + std::to_string(getpid()));
        std::filesystem::create_directories(dir);
        // A buffer file next to the scene, so inputs that reference "buffer.bin" reach the accessor code.
        std::ofstream(dir / "buffer.bin", std::ios::binary) << std::string(256, '\x3f');
        // Image files next to the scene for URI images: the seeds' 8x8 checker PNG, truncated, and a
        // bare JPEG start-of-image marker.
        std::ifstream seed(std::filesystem::path(TESSERA_FUZZ_SEEDS) / "checker.png", std::ios::binary);
        std::string png((std::istreambuf_iterator<char>(seed)), std::istreambuf_iterator<char>());
        std::ofstream(dir / "checker.png", std::ios::binary) << png;
        std::ofstream(dir / "truncated.png", std::ios::binary) << png.substr(0, png.size() / 2);
        std::ofstream(dir / "image.jpg", std::ios::binary) << std::string("\xff\xd8\xff\xe0\x00\x10JFIF\x00", 11);
        return (dir / "scene").string();
    }();
    return path;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const bool glb = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
    const std::string path = scenePath() + (glb ? ".glb" : ".gltf");
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    }
    std::vector<std::string> warnings;
    tessera::SceneLoadOptions options;
    options.maxFileBytes = 1 << 20;
    try {
        tessera::Scene scene = tessera::loadGltfScene(path, warnings, options);
        (void)scene;
    } catch (const tessera::InputError&) {
    }
    return 0;
}
