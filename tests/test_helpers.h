#pragma once
// Small helpers shared by the tests: procedural scenes and paths to the project's files.
#include <filesystem>
#include <string>

#include "scene/scene.h"

namespace tessera::test {

inline std::string sourcePath(const std::string& relative) { return std::string(TESSERA_SOURCE_DIR) + "/" + relative; }

/// A fresh, empty temporary directory for one test.
inline std::filesystem::path tempDir(const std::string& name) {
    std::filesystem::path p = std::filesystem::temp_directory_path() / ("tessera-test-" + name);
    std::filesystem::remove_all(p);
    std::filesystem::create_directories(p);
    return p;
}

/// A UV sphere as a triangle mesh (outward winding), for tests that need many triangles.
inline TriangleMesh makeUvSphereMesh(Vec3f center, float radius, int rings, int segments, uint32_t material) {
    TriangleMesh m;
    m.name = "uv-sphere";
    m.materialId = material;
    for (int r = 0; r <= rings; ++r) {
        float theta = kPi * float(r) / float(rings);
        for (int s = 0; s <= segments; ++s) {
            float phi = 2.f * kPi * float(s) / float(segments);
            m.positions.push_back(center + radius * Vec3f(std::sin(theta) * std::cos(phi), std::cos(theta),
                                                          std::sin(theta) * std::sin(phi)));
        }
    }
    auto id = [&](int r, int s) { return uint32_t(r * (segments + 1) + s); };
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            if (r > 0) m.triangles.emplace_back(id(r, s), id(r, s + 1), id(r + 1, s));
            if (r < rings - 1) m.triangles.emplace_back(id(r, s + 1), id(r + 1, s + 1), id(r + 1, s));
        }
    return m;
}

}  // namespace tessera::test
