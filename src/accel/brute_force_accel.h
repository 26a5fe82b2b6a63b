#pragma once
/// \file brute_force_accel.h
/// Tests every primitive against every ray: the reference the other backends are checked against.
#include "accel/accel.h"

namespace tessera {

class BruteForceAccel final : public Accel {
public:
    explicit BruteForceAccel(const SceneGeometry& geometry);
    std::string_view name() const override { return "brute"; }
    bool intersect(const Ray& ray, Hit& hit) const override;
    bool occluded(const Ray& ray) const override;
    Bounds3f bounds() const override { return bounds_; }
    AccelStats stats() const override;

private:
    const SceneGeometry& geometry_;
    Bounds3f bounds_;
};

}  // namespace tessera
