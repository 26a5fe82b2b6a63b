// libFuzzer target: any byte string given to the glTF loader must either load or throw an
// InputError, never crash, hang or leak (run under ASan+UBSan by tools/fuzz.sh).
#include <unistd.h>

#include <cstdint>
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
        return (dir / "scene.gltf").string();
    }();
    return path;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = scenePath();
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
