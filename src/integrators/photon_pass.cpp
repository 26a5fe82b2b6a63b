#include "integrators/photon_pass.h"

#include <algorithm>
#include <vector>

namespace tessera {

float photonIterationRadius(float radius, float alpha, uint32_t iteration) {
    double r2 = double(radius) * double(radius);
    for (uint32_t k = 1; k <= iteration; ++k) r2 *= (double(k) + double(alpha)) / double(k + 1);
    return float(std::sqrt(r2));
}

float defaultMergeRadius(const RenderContext& ctx, uint64_t paths) {
    const double n = double(std::max<uint64_t>(paths, 1));
    const float fromScene = float(0.003 * double(ctx.scene.lights().sceneRadius()) * std::sqrt(std::max(1.0, 262144.0 / n)));
    const int w = ctx.camera.width(), h = ctx.camera.height();
    std::vector<float> footprints;
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 16; ++i) {
            Ray ray = ctx.camera.generateRay(Vec2f((float(i) + 0.5f) * float(w) / 16.f, (float(j) + 0.5f) * float(h) / 16.f), Vec2f(0.5f));
            Hit hit;
            if (ctx.accel.intersect(ray, hit)) footprints.push_back(ctx.camera.pixelFootprint(ray.o + hit.t * ray.d));
        }
    if (footprints.empty()) return fromScene;
    std::nth_element(footprints.begin(), footprints.begin() + long(footprints.size() / 2), footprints.end());
    const float fromView = footprints[footprints.size() / 2] * float(std::sqrt(double(w) * double(h) / n));
    return fromView > 0.f ? std::min(fromScene, fromView) : fromScene;
}

}  // namespace tessera
