#include "accel/instanced_accel.h"

#include <chrono>

#include "geometry/instances.h"

namespace tessera {

InstancedAccel::InstancedAccel(const SceneGeometry& geometry, const Factory& makeFlat) : geometry_(geometry) {
    auto start = std::chrono::steady_clock::now();
    flat_ = makeFlat(geometry);  // its builders see only the flat meshes and spheres
    size_t memory = flat_->stats().memoryBytes;
    std::vector<bool> used(geometry.prototypes.size(), false);
    for (const MeshInstance& inst : geometry.instances) used[inst.prototype] = true;
    prototypes_.resize(geometry.prototypes.size());
    std::vector<Bounds3f> objectBounds(geometry.prototypes.size());
    for (size_t p = 0; p < geometry.prototypes.size(); ++p) {
        if (!used[p]) continue;
        prototypes_[p] = makeFlat(geometry.prototypes[p]);
        objectBounds[p] = geometry.prototypes[p].bounds();
        memory += prototypes_[p]->stats().memoryBytes;
    }
    std::vector<Bounds3f> boxes;
    for (uint32_t i = 0; i < geometry.instances.size(); ++i) {
        Bounds3f b = instanceWorldBounds(geometry.instances[i], objectBounds[geometry.instances[i].prototype]);
        if (!finiteBounds(b)) continue;  // an empty prototype, or one the transform sends to infinity
        boxes.push_back(b);
        topInstances_.push_back(i);
    }
    BvhConfig config;
    config.sahBlockSize = 1;  // an instance is visited alone
    config.maxLeafSize = 1;
    top_ = buildBinaryBvh(boxes, config);
    memory += top_.nodes.size * sizeof(BvhBuildNode) + top_.primIndices.size() * sizeof(uint32_t) +
              topInstances_.size() * sizeof(uint32_t) + geometry.instances.size() * sizeof(MeshInstance);
    bounds_ = flat_->bounds();
    for (const Bounds3f& b : boxes) bounds_.extend(b);
    stats_.memoryBytes = memory;
    stats_.primitives = geometry.primitiveCount() + geometry.instancedPrimitiveCount();
    stats_.buildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

namespace {

/// Entry distance of the ray into `b` within [tMin, tMax], or +inf when it misses. A NaN from
/// 0 · inf (origin on a slab plane of an axis the ray is parallel to) leaves that slab open.
inline float enterBox(const Bounds3f& b, const Vec3f& o, const Vec3f& invD, float tMin, float tMax) {
    float tNear = tMin, tFar = tMax;
    for (int a = 0; a < 3; ++a) {
        float t0 = (b.lower[a] - o[a]) * invD[a], t1 = (b.upper[a] - o[a]) * invD[a];
        if (t0 > t1) std::swap(t0, t1);
        tNear = t0 > tNear ? t0 : tNear;
        tFar = t1 < tFar ? t1 : tFar;
    }
    // Ize 2013 ("Robust BVH Ray Traversal"): 2 ulps of slack on the far side close the holes rounding opens.
    return tNear <= tFar * (1.f + 4.f * 0x1p-24f) ? tNear : kInfinity;
}

}  // namespace

template <class Visit, class TMax> void InstancedAccel::traverseTop(const Ray& ray, TMax tMax, Visit visit) const {
    if (top_.primIndices.empty()) return;
    Vec3f invD(1.f / ray.d.x, 1.f / ray.d.y, 1.f / ray.d.z);
    struct Entry {
        uint32_t node;
        float tEnter;
    };
    Entry stack[128];
    int size = 0;
    float t0 = enterBox(top_.nodes[0].bounds, ray.o, invD, ray.tMin, tMax());
    if (t0 == kInfinity) return;
    stack[size++] = {0, t0};
    while (size > 0) {
        Entry e = stack[--size];
        if (e.tEnter > tMax()) continue;
        const BvhBuildNode& n = top_.nodes[e.node];
        if (n.isLeaf()) {
            for (uint32_t k = 0; k < n.count; ++k)
                if (visit(topInstances_[top_.primIndices[n.first() + k]])) return;
            continue;
        }
        float tl = enterBox(top_.nodes[n.left].bounds, ray.o, invD, ray.tMin, tMax());
        float tr = enterBox(top_.nodes[n.right].bounds, ray.o, invD, ray.tMin, tMax());
        // Push the farther first so the nearer is visited first; ties keep left before right.
        Entry left{n.left, tl}, right{n.right, tr};
        Entry first = tr < tl ? right : left, second = tr < tl ? left : right;
        if (second.tEnter != kInfinity) stack[size++] = second;
        if (first.tEnter != kInfinity) stack[size++] = first;
    }
}

bool InstancedAccel::intersectWith(const Ray& ray, Hit& hit, bool coherent) const {
    if (!isTraceableRay(ray)) return false;
    bool found = coherent ? flat_->intersectCoherent(ray, hit) : flat_->intersect(ray, hit);
    float best = found ? hit.t : ray.tMax;
    traverseTop(
        ray, [&] { return best; },
        [&](uint32_t i) {
            const MeshInstance& inst = geometry_.instances[i];
            Ray local = rayToObject(inst, ray);
            local.tMax = best;
            Hit h;
            if (prototypes_[inst.prototype]->intersect(local, h) && h.t < best) {
                best = h.t;
                h.instId = i;
                h.ng = instanceNormalToWorld(inst, h.ng);
                hit = h;
                found = true;
            }
            return false;
        });
    return found;
}

bool InstancedAccel::occluded(const Ray& ray) const {
    if (!isTraceableRay(ray)) return false;
    if (flat_->occluded(ray)) return true;
    bool blocked = false;
    traverseTop(
        ray, [&] { return ray.tMax; },
        [&](uint32_t i) {
            const MeshInstance& inst = geometry_.instances[i];
            blocked = prototypes_[inst.prototype]->occluded(rayToObject(inst, ray));
            return blocked;
        });
    return blocked;
}

}  // namespace tessera
