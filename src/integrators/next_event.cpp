#include "integrators/next_event.h"

namespace tessera {

bool sampleNextEvent(const LightSet& lights, const Vec3f& p, const Vec3f& ng, const Vec3f& woWorld, Sampler& sampler,
                     NextEventSample& out) {
    if (lights.empty()) return false;
    out.pRef = offsetRayOrigin(p, glm::dot(woWorld, ng) >= 0.f ? ng : -ng);
    float uPick = sampler.get1D();
    Vec2f uLight = sampler.get2D();
    return lights.sample(out.pRef, uPick, uLight, out.light) && !isBlack(out.light.Le);
}

}  // namespace tessera
