#pragma once
/// \file bounds.h
/// Axis-aligned bounding boxes.
#include "core/math.h"

namespace tessera {

struct Bounds3f {
    Vec3f lower{kInfinity};
    Vec3f upper{-kInfinity};

    bool empty() const { return lower.x > upper.x || lower.y > upper.y || lower.z > upper.z; }
    void extend(const Vec3f& p) {
        lower = glm::min(lower, p);
        upper = glm::max(upper, p);
    }
    void extend(const Bounds3f& b) {
        lower = glm::min(lower, b.lower);
        upper = glm::max(upper, b.upper);
    }
    Vec3f diagonal() const { return empty() ? Vec3f(0.f) : upper - lower; }
    Vec3f center() const { return 0.5f * (lower + upper); }
    /// Half the surface area, 0 for an empty box: the SAH compares ratios of areas, so builders
    /// need no factor 2.
    float halfArea() const {
        Vec3f d = diagonal();
        return d.x * d.y + d.y * d.z + d.z * d.x;
    }
    float surfaceArea() const { return 2.f * halfArea(); }
    /// The common part of two boxes (empty when they do not meet).
    Bounds3f intersection(const Bounds3f& other) const {
        Bounds3f r;
        r.lower = glm::max(lower, other.lower);
        r.upper = glm::min(upper, other.upper);
        return r;
    }
};

}  // namespace tessera
