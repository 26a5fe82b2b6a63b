#include "geometry/shapes.h"

namespace tessera {

size_t SceneGeometry::primitiveCount() const {
    size_t n = spheres.size();
    for (const TriangleMesh& m : meshes) n += m.triangles.size();
    return n;
}

Bounds3f SceneGeometry::bounds() const {
    Bounds3f b;
    for (const TriangleMesh& m : meshes)
        for (const Vec3f& p : m.positions) b.extend(p);
    for (const Sphere& s : spheres) b.extend(sphereBounds(s));
    return b;
}

}  // namespace tessera
