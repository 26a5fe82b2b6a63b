#pragma once
/// \file instanced_accel.h
/// The two-level structure of our own backends (bvh, sbvh, kdtree, brute) for scenes with mesh
/// instances (SceneGeometry::instances): one bottom-level structure of the chosen kind per
/// prototype, in object space, built once however many instances place it; one of the same kind
/// over the flat meshes and spheres; and a top-level binary BVH over the instances' world boxes
/// (buildBinaryBvh, the builder our BVH uses). A ray entering an instance's box is transformed to
/// its object space (rayToObject) and traced through the prototype's structure with the closest t
/// so far as tMax; t is the same in both spaces. Embree has its own instancing (embree_accel.cpp).
/// Traversal visits children nearest first and is deterministic: the same record for any thread.
#include <functional>
#include <memory>
#include <vector>

#include "accel/accel.h"
#include "accel/bvh_builder.h"

namespace tessera {

class InstancedAccel final : public Accel {
public:
    using Factory = std::function<std::unique_ptr<Accel>(const SceneGeometry&)>;
    /// `makeFlat` builds one structure of the chosen kind over a SceneGeometry's flat geometry.
    InstancedAccel(const SceneGeometry& geometry, const Factory& makeFlat);

    std::string_view name() const override { return flat_->name(); }
    bool intersect(const Ray& ray, Hit& hit) const override { return intersectWith(ray, hit, false); }
    bool intersectCoherent(const Ray& ray, Hit& hit) const override { return intersectWith(ray, hit, true); }
    bool occluded(const Ray& ray) const override;
    Bounds3f bounds() const override { return bounds_; }
    /// memoryBytes: every structure (flat, bottom levels, top level and instance records).
    AccelStats stats() const override { return stats_; }

    const Accel& flatStructure() const { return *flat_; }
    const Accel* prototypeStructure(uint32_t prototype) const { return prototypes_[prototype].get(); }

private:
    bool intersectWith(const Ray& ray, Hit& hit, bool coherent) const;
    /// Calls visit(instance) for each instance whose box the ray enters before tMax() (read again
    /// after every visit), nearest box first; stops when visit returns true.
    template <class Visit, class TMax> void traverseTop(const Ray& ray, TMax tMax, Visit visit) const;

    const SceneGeometry& geometry_;
    std::unique_ptr<Accel> flat_;
    std::vector<std::unique_ptr<Accel>> prototypes_;  ///< null for a prototype no instance uses
    BinaryBvh top_;
    std::vector<uint32_t> topInstances_;  ///< top_ primitive index → instance index
    Bounds3f bounds_;
    AccelStats stats_;
};

}  // namespace tessera
