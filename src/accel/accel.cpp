#include "accel/accel.h"

#include "accel/brute_force_accel.h"
#include "accel/bvh_accel.h"
#include "accel/embree_accel.h"
#include "accel/instanced_accel.h"
#include "accel/kdtree_accel.h"
#include "core/error.h"

namespace tessera {

std::vector<std::string> accelNames() { return {"embree", "bvh", "sbvh", "kdtree", "brute"}; }

namespace {

/// One structure of our own over the flat meshes and spheres of `geometry`; null for an unknown name.
std::unique_ptr<Accel> createFlatAccel(std::string_view name, const SceneGeometry& geometry, const AccelOptions& options) {
    if (name == "bvh") return std::make_unique<BvhAccel>(geometry, options);
    if (name == "sbvh") {
        BvhConfig config;
        config.spatialSplits = true;
        return std::make_unique<BvhAccel>(geometry, options, config);
    }
    if (name == "kdtree") return std::make_unique<KdTreeAccel>(geometry, options);
    if (name == "brute") return std::make_unique<BruteForceAccel>(geometry);
    return nullptr;
}

}  // namespace

std::unique_ptr<Accel> createAccel(std::string_view name, const SceneGeometry& geometry, const AccelOptions& options) {
    if (name == "embree") return std::make_unique<EmbreeAccel>(geometry, options);  // instances through Embree's own API
    auto makeFlat = [&](const SceneGeometry& g) { return createFlatAccel(name, g, options); };
    bool ours = name == "bvh" || name == "sbvh" || name == "kdtree" || name == "brute";
    if (ours && !geometry.instances.empty()) return std::make_unique<InstancedAccel>(geometry, makeFlat);
    if (std::unique_ptr<Accel> flat = makeFlat(geometry)) return flat;
    std::string known;
    for (const std::string& n : accelNames()) known += (known.empty() ? "" : ", ") + n;
    throw InputError("unknown acceleration structure '" + std::string(name) + "' (known: " + known + ")");
}

}  // namespace tessera
