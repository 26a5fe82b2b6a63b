#include "accel/accel.h"

#include "accel/brute_force_accel.h"
#include "accel/bvh_accel.h"
#include "accel/embree_accel.h"
#include "accel/kdtree_accel.h"
#include "core/error.h"

namespace tessera {

std::vector<std::string> accelNames() { return {"embree", "bvh", "sbvh", "kdtree", "brute"}; }

std::unique_ptr<Accel> createAccel(std::string_view name, const SceneGeometry& geometry, const AccelOptions& options) {
    if (name == "embree") return std::make_unique<EmbreeAccel>(geometry, options);
    if (name == "bvh") return std::make_unique<BvhAccel>(geometry, options);
    if (name == "sbvh") {
        BvhConfig config;
        config.spatialSplits = true;
        return std::make_unique<BvhAccel>(geometry, options, config);
    }
    if (name == "kdtree") return std::make_unique<KdTreeAccel>(geometry, options);
    if (name == "brute") return std::make_unique<BruteForceAccel>(geometry);
    std::string known;
    for (const std::string& n : accelNames()) known += (known.empty() ? "" : ", ") + n;
    throw InputError("unknown acceleration structure '" + std::string(name) + "' (known: " + known + ")");
}

}  // namespace tessera
