#pragma once
/// \file embree_accel.h
/// Embree 3 backend: the production default and the oracle our own structures are validated against.
/// Triangles use Embree's native triangle geometry (build quality MEDIUM: binned SAH BVH8). Spheres
/// use our double-precision test, because Embree's float sphere primitive shows acne on the
/// radius-1e4 walls of the sphere Cornell box: up to kDirectSphereCount of them are tested in a loop
/// after Embree's triangle query, more are Embree user geometry calling the same test. Mesh instances
/// use Embree's instance API: a scene per prototype, an RTC_GEOMETRY_TYPE_INSTANCE per instance.
#include <vector>

#include "accel/accel.h"

namespace tessera {

class EmbreeAccel final : public Accel {
public:
    EmbreeAccel(const SceneGeometry& geometry, const AccelOptions& options);
    ~EmbreeAccel() override;
    EmbreeAccel(const EmbreeAccel&) = delete;
    EmbreeAccel& operator=(const EmbreeAccel&) = delete;

    std::string_view name() const override { return "embree"; }
    bool intersect(const Ray& ray, Hit& hit) const override;
    bool intersectCoherent(const Ray& ray, Hit& hit) const override;
    bool occluded(const Ray& ray) const override;
    Bounds3f bounds() const override { return bounds_; }
    AccelStats stats() const override { return stats_; }

private:
    bool intersectWith(const Ray& ray, Hit& hit, bool coherent) const;
    /// Embree geometry id of instance 0 (the flat meshes, then the spheres, come first).
    uint32_t instanceGeomBase() const { return geometry_.sphereGeomId() + 1; }

    /// Embree's user-geometry path (a callback per candidate, and a scene of two primitive types)
    /// costs more per ray than a loop over a few spheres. `ptnee` instructions per sample against
    /// user geometry for every sphere count (callgrind, 64x64): -14% with 1 sphere (bdpt, the
    /// SmallVCM Cornell box), -5% with 3, -11% with 9, -6% with 16; +13% with 32.
    static constexpr size_t kDirectSphereCount = 16;
    bool directSpheres_ = false;  // spheres tested by the loop, not attached to Embree's scene
    const SceneGeometry& geometry_;
    void* device_ = nullptr;  // RTCDevice, kept opaque so embree headers stay out of this header
    void* scene_ = nullptr;   // RTCScene
    std::vector<void*> prototypeScenes_;  // RTCScene per prototype (null where no instance uses it)
    Bounds3f bounds_;
    AccelStats stats_;
};

}  // namespace tessera
