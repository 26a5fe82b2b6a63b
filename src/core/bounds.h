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
    float surfaceArea() const {
        Vec3f d = diagonal();
        return 2.f * (d.x * d.y + d.y * d.z + d.z * d.x);
    }
};

}  // namespace tessera
