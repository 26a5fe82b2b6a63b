#include "geometry/shapes.h"

#include "geometry/instances.h"

namespace tessera {

size_t SceneGeometry::primitiveCount() const {
    size_t n = spheres.size();
    for (const TriangleMesh& m : meshes) n += m.triangles.size();
    return n;
}

size_t SceneGeometry::instancedPrimitiveCount() const {
    size_t n = 0;
    for (const MeshInstance& inst : instances) n += prototypes[inst.prototype].primitiveCount();
    return n;
}

Bounds3f SceneGeometry::bounds() const {
    Bounds3f b;
    for (const TriangleMesh& m : meshes)
        for (const Vec3f& p : m.positions) b.extend(p);
    for (const Sphere& s : spheres) b.extend(sphereBounds(s));
    if (!instances.empty()) {
        std::vector<Bounds3f> objectBounds;
        for (const SceneGeometry& proto : prototypes) objectBounds.push_back(proto.bounds());
        for (const MeshInstance& inst : instances) b.extend(instanceWorldBounds(inst, objectBounds[inst.prototype]));
    }
    return b;
}

}  // namespace tessera
