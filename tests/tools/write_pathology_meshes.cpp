// Writes the large meshes of the pathology battery (tests/accel_pathologies.h) as OBJ files, so that
// `tessera validate-accel` and `bench-accel` can be run on exactly the meshes the tests use.
// Usage: write_pathology_meshes DIR   (writes DIR/integer-lattice.obj and DIR/sliver-hairball.obj)
#include <cstdio>
#include <filesystem>
#include <string>

#include "accel_pathologies.h"

namespace {

/// Positions with 9 significant digits, which read back as the same float.
bool writeObj(const tessera::TriangleMesh& m, const std::filesystem::path& path) {
    std::FILE* f = std::fopen(path.c_str(), "w");
    if (!f) return false;
    std::fprintf(f, "# %s: %zu triangles (tests/accel_pathologies.h)\n", m.name.c_str(), m.triangles.size());
    for (const tessera::Vec3f& p : m.positions) std::fprintf(f, "v %.9g %.9g %.9g\n", p.x, p.y, p.z);
    for (const glm::uvec3& t : m.triangles) std::fprintf(f, "f %u %u %u\n", t.x + 1, t.y + 1, t.z + 1);
    return std::fclose(f) == 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: write_pathology_meshes DIR\n");
        return 2;
    }
    std::filesystem::path dir(argv[1]);
    bool ok = writeObj(tessera::test::integerLattice().meshes[0], dir / "integer-lattice.obj") &&
              writeObj(tessera::test::sliverHairball().meshes[0], dir / "sliver-hairball.obj");
    if (!ok) std::fprintf(stderr, "write_pathology_meshes: cannot write to %s\n", argv[1]);
    return ok ? 0 : 1;
}
