// libFuzzer target: any byte string given to the PLY or OBJ loader (PLY when it starts with
// "ply", OBJ otherwise; gzip-compressed input is inflated by both) must either load or throw an
// InputError naming the problem, never crash, hang or leak (run under ASan+UBSan by tools/fuzz.sh).
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.h"
#include "scene/mesh_loader.h"

namespace {
std::string meshPath(const char* extension) {
    static const std::filesystem::path dir = [] {
        auto d = std::filesystem::temp_directory_path() / ("tessera-fuzz-mesh-" + std::to_string(getpid()));
        std::filesystem::create_directories(d);
        return d;
    }();
    return (dir / (std::string("mesh") + extension)).string();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    bool ply = size >= 3 && std::memcmp(data, "ply", 3) == 0;
    const std::string path = meshPath(ply ? ".ply" : ".obj");
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    }
    tessera::MeshLoadOptions options;
    options.maxBytes = 16 << 20;  // gzip bombs stop here, well under libFuzzer's RSS limit
    try {
        tessera::TriangleMesh mesh = ply ? tessera::loadPlyMesh(path, options) : tessera::loadObjMesh(path, options);
        // Whatever loads must be usable: every index names a vertex.
        for (const auto& t : mesh.triangles)
            if (t.x >= mesh.positions.size() || t.y >= mesh.positions.size() || t.z >= mesh.positions.size()) __builtin_trap();
    } catch (const tessera::InputError&) {
    }
    return 0;
}
