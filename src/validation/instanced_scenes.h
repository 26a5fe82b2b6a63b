#pragma once
/// \file instanced_scenes.h
/// Validating structures on scenes with mesh instances. The validator's checks read world-space
/// triangles by (geomId, primId); an instance hit names its prototype's mesh in object space. So
/// both the tested structure and the reference are seen through FlattenedIds, which renumbers
/// every record into the scene's flattened copy (InstanceFlattening), and the comparison runs on
/// that copy: a hit on instance i, mesh g, triangle p is the copy's triangle p of mesh
/// flatGeomId(i, g), at the same place. A structure can then also be compared against any
/// structure built over the flattened copy itself (Embree or brute force, flat).
#include "accel/accel.h"
#include "geometry/instances.h"

namespace tessera {

class FlattenedIds final : public Accel {
public:
    FlattenedIds(const Accel& inner, const InstanceFlattening& flattening) : inner_(inner), flattening_(flattening) {}
    std::string_view name() const override { return inner_.name(); }
    bool intersect(const Ray& ray, Hit& hit) const override {
        Hit h;
        if (!inner_.intersect(ray, h)) return false;
        hit = flattening_.toFlat(h);
        return true;
    }
    bool intersectCoherent(const Ray& ray, Hit& hit) const override {
        Hit h;
        if (!inner_.intersectCoherent(ray, h)) return false;
        hit = flattening_.toFlat(h);
        return true;
    }
    bool occluded(const Ray& ray) const override { return inner_.occluded(ray); }
    Bounds3f bounds() const override { return inner_.bounds(); }
    AccelStats stats() const override { return inner_.stats(); }

private:
    const Accel& inner_;
    const InstanceFlattening& flattening_;
};

}  // namespace tessera
