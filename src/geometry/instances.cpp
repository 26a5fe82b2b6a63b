#include "geometry/instances.h"

#include <glm/mat3x3.hpp>

namespace tessera {

bool makeMeshInstance(uint32_t prototype, const Mat4d& objectToWorld, MeshInstance& out) {
    double det = glm::determinant(glm::dmat3(objectToWorld));
    if (!(std::abs(det) > 0.0) || !std::isfinite(det)) return false;
    Mat4d inverse = glm::inverse(objectToWorld);
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(inverse[c][r]) || !std::isfinite(objectToWorld[c][r])) return false;
    out.prototype = prototype;
    out.objectToWorld = Mat4f(objectToWorld);
    out.worldToObject = Mat4f(inverse);
    return true;
}

Ray rayToObject(const MeshInstance& inst, const Ray& r) {
    Ray o = r;
    o.o = Vec3f(inst.worldToObject * Vec4f(r.o, 1.f));
    o.d = Vec3f(inst.worldToObject * Vec4f(r.d, 0.f));
    return o;
}

Vec3f instancePointToWorld(const MeshInstance& inst, const Vec3f& p) { return Vec3f(inst.objectToWorld * Vec4f(p, 1.f)); }

Vec3f instanceNormalToWorld(const MeshInstance& inst, const Vec3f& n) {
    Vec3f w = glm::transpose(glm::mat3(inst.worldToObject)) * n;
    float len2 = glm::dot(w, w);
    if (!(len2 > 0.f) || !std::isfinite(len2)) return Vec3f(0.f);
    return w / std::sqrt(len2);
}

Vec4f instanceTangentToWorld(const MeshInstance& inst, const Vec4f& t) {
    Vec3f d = glm::mat3(inst.objectToWorld) * Vec3f(t);
    float len = glm::length(d);
    return Vec4f(len > 0.f && std::isfinite(len) ? d / len : Vec3f(0.f), instanceMirrors(inst) ? -t.w : t.w);
}

Bounds3f instanceWorldBounds(const MeshInstance& inst, const Bounds3f& box) {
    Bounds3f b;
    if (box.empty()) return b;
    for (int i = 0; i < 8; ++i) {
        Vec3d corner((i & 1) ? box.upper.x : box.lower.x, (i & 2) ? box.upper.y : box.lower.y, (i & 4) ? box.upper.z : box.lower.z);
        b.extend(Vec3f(Mat4d(inst.objectToWorld) * glm::dvec4(corner, 1.0)));
    }
    // The object-space ray and the float transform round; a relative pad covers both.
    float pad = 1e-5f * std::max(maxComponent(glm::abs(b.lower)), maxComponent(glm::abs(b.upper)));
    b.lower -= Vec3f(pad);
    b.upper += Vec3f(pad);
    return b;
}

bool instanceMirrors(const MeshInstance& inst) { return glm::determinant(glm::mat3(inst.objectToWorld)) < 0.f; }

InstanceFlattening::InstanceFlattening(const SceneGeometry& g) : g_(g) {
    uint32_t next = uint32_t(g.meshes.size());
    firstMesh_.reserve(g.instances.size());
    for (const MeshInstance& inst : g.instances) {
        firstMesh_.push_back(next);
        next += uint32_t(g.prototypes[inst.prototype].meshes.size());
    }
    meshCount_ = next;
}

SceneGeometry InstanceFlattening::flatten() const {
    SceneGeometry out;
    out.meshes = g_.meshes;
    out.spheres = g_.spheres;
    out.maskImages = g_.maskImages;
    out.meshes.reserve(meshCount_);
    for (const MeshInstance& inst : g_.instances) {
        bool mirror = instanceMirrors(inst);
        for (const TriangleMesh& m : g_.prototypes[inst.prototype].meshes) {
            TriangleMesh w = m;
            for (Vec3f& p : w.positions) p = instancePointToWorld(inst, p);
            for (Vec3f& n : w.normals) n = instanceNormalToWorld(inst, n);
            for (Vec4f& t : w.tangents) t = instanceTangentToWorld(inst, t);
            if (mirror)
                for (glm::uvec3& t : w.triangles) std::swap(t.y, t.z);
            out.meshes.push_back(std::move(w));
        }
    }
    return out;
}

Hit InstanceFlattening::toFlat(const Hit& hit) const {
    Hit h = hit;
    if (hit.instId != kInvalidId) {
        h.geomId = flatGeomId(hit.instId, hit.geomId);
        h.instId = kInvalidId;
        // The copy's flipped winding swaps vertices 1 and 2, whose barycentrics (u, v) are.
        if (instanceMirrors(g_.instances[hit.instId])) std::swap(h.u, h.v);
    } else if (hit.geomId == g_.sphereGeomId()) {
        h.geomId = meshCount_;
    }
    return h;
}

}  // namespace tessera
