#include "accel/embree_accel.h"

#include <embree3/rtcore.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "accel/mixed_leaf.h"
#include "geometry/alpha_mask.h"
#include "geometry/instances.h"
#include "geometry/intersect.h"

namespace tessera {
namespace {

void embreeErrorCallback(void*, RTCError code, const char* message) {
    // Embree reports programming errors (invalid arguments) and out-of-memory here; both are fatal
    // for a render, so surface them as exceptions at the call site instead of silent garbage.
    if (code == RTC_ERROR_NONE) return;
    throw std::runtime_error(std::string("Embree error ") + std::to_string(int(code)) + ": " +
                             (message ? message : ""));
}

const SceneGeometry* geometryOf(void* userPtr) { return static_cast<const SceneGeometry*>(userPtr); }

void sphereBoundsFn(const RTCBoundsFunctionArguments* args) {
    const Sphere& s = geometryOf(args->geometryUserPtr)->spheres[args->primID];
    Bounds3f b = paddedSphereBounds(s);  // the same box as our structures
    args->bounds_o->lower_x = b.lower.x;
    args->bounds_o->lower_y = b.lower.y;
    args->bounds_o->lower_z = b.lower.z;
    args->bounds_o->upper_x = b.upper.x;
    args->bounds_o->upper_y = b.upper.y;
    args->bounds_o->upper_z = b.upper.z;
}

Ray rayFromEmbree(RTCRayN* ray, unsigned N, unsigned i) {
    Ray r;
    r.o = {RTCRayN_org_x(ray, N, i), RTCRayN_org_y(ray, N, i), RTCRayN_org_z(ray, N, i)};
    r.d = {RTCRayN_dir_x(ray, N, i), RTCRayN_dir_y(ray, N, i), RTCRayN_dir_z(ray, N, i)};
    r.tMin = RTCRayN_tnear(ray, N, i);
    r.tMax = RTCRayN_tfar(ray, N, i);
    return r;
}

void sphereIntersectFn(const RTCIntersectFunctionNArguments* args) {
    const SceneGeometry* geometry = geometryOf(args->geometryUserPtr);
    const Sphere& s = geometry->spheres[args->primID];
    RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, args->N);
    RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, args->N);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        Ray r = rayFromEmbree(ray, args->N, i);
        double t = intersectSphere(s.center, s.radius, r);
        // t < tMax in double may still round up to tMax: every backend then skips it.
        if (t < 0.0 || !(float(t) < r.tMax)) continue;
        // Only t and the ids: intersectWith builds the record of the closest hit (sphereHitRecord).
        RTCRayN_tfar(ray, args->N, i) = float(t);
        RTCHitN_primID(hit, args->N, i) = args->primID;
        RTCHitN_geomID(hit, args->N, i) = args->geomID;
        RTCHitN_instID(hit, args->N, i, 0) = args->context->instID[0];
    }
}

void sphereOccludedFn(const RTCOccludedFunctionNArguments* args) {
    const Sphere& s = geometryOf(args->geometryUserPtr)->spheres[args->primID];
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        Ray r = rayFromEmbree(args->ray, args->N, i);
        double t = intersectSphere(s.center, s.radius, r);
        if (t >= 0.0 && float(t) < r.tMax) RTCRayN_tfar(args->ray, args->N, i) = -kInfinity;
    }
}

/// Intersection and occlusion filter of cut-out meshes (glTF alphaMode MASK): drops the hits their
/// alpha mask drops, and Embree goes on to the next candidate. The decision uses the barycentrics of
/// our watertight test (geometry/intersect.h) on the same ray and triangle, not Embree's own
/// (Möller's, a few ulps apart): every other backend decides with exactly those, so a hit within
/// rounding of the mask's cutoff contour is kept or dropped alike everywhere, and hit records stay
/// identical across backends. Where the watertight test misses the triangle (a ray grazing an edge
/// that only Möller's test hits) Embree's barycentrics decide.
void alphaFilterFn(const RTCFilterFunctionNArguments* args) {
    const SceneGeometry* geometry = geometryOf(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        uint32_t geomId = RTCHitN_geomID(args->hit, args->N, i), primId = RTCHitN_primID(args->hit, args->N, i);
        const TriangleMesh& mesh = geometry->meshes[geomId];
        float u = RTCHitN_u(args->hit, args->N, i), v = RTCHitN_v(args->hit, args->N, i);
        Ray r = rayFromEmbree(args->ray, args->N, i);
        r.tMin = -kInfinity, r.tMax = kInfinity;  // only the barycentrics matter here
        const glm::uvec3& tri = mesh.triangles[primId];
        TriangleHit th;
        if (intersectTriangle(r, mesh.positions[tri.x], mesh.positions[tri.y], mesh.positions[tri.z], th)) u = th.u, v = th.v;
        if (!alphaMaskKeeps(mesh, primId, u, v)) args->valid[i] = 0;
    }
}

void fillRay(const Ray& r, RTCRay& er) {
    er.org_x = r.o.x;
    er.org_y = r.o.y;
    er.org_z = r.o.z;
    er.dir_x = r.d.x;
    er.dir_y = r.d.y;
    er.dir_z = r.d.z;
    er.tnear = r.tMin;
    er.tfar = r.tMax;
    er.time = 0.f;
    er.mask = 0xffffffffu;
    er.id = 0;
    er.flags = 0;
}

/// Attaches the meshes of `geometry` (flat meshes, or a prototype's) to `scene` by their geomId.
void attachMeshes(RTCDevice device, RTCScene scene, const SceneGeometry& geometry) {
    for (uint32_t g = 0; g < geometry.meshes.size(); ++g) {
        const TriangleMesh& mesh = geometry.meshes[g];
        if (mesh.triangles.empty()) continue;  // ids stay aligned: attached by id below
        RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        // Embree reads vertices with 16-byte loads: the buffer it allocates is padded for that.
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                              3 * sizeof(float), mesh.positions.size()));
        std::memcpy(v, mesh.positions.data(), mesh.positions.size() * sizeof(Vec3f));
        auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(uint32_t), mesh.triangles.size()));
        std::memcpy(idx, mesh.triangles.data(), mesh.triangles.size() * sizeof(glm::uvec3));
        if (mesh.alphaMask) {
            // Filters on cut-out meshes only: scenes without them run Embree's unfiltered kernels.
            if (!rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED))
                throw std::runtime_error("Embree was built without filter functions: cannot render the alpha mask of " + mesh.name);
            rtcSetGeometryUserData(geom, const_cast<SceneGeometry*>(&geometry));
            rtcSetGeometryIntersectFilterFunction(geom, alphaFilterFn);
            rtcSetGeometryOccludedFilterFunction(geom, alphaFilterFn);
        }
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(scene, geom, g);
        rtcReleaseGeometry(geom);
    }
}

}  // namespace

EmbreeAccel::EmbreeAccel(const SceneGeometry& geometry, const AccelOptions& options) : geometry_(geometry) {
    auto start = std::chrono::steady_clock::now();
    std::string config = options.threads > 0 ? "threads=" + std::to_string(options.threads) : std::string();
    RTCDevice device = rtcNewDevice(config.c_str());
    if (!device) throw std::runtime_error("Embree: cannot create a device (error " + std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
    device_ = device;
    rtcSetDeviceErrorFunction(device, embreeErrorCallback, nullptr);

    RTCScene scene = rtcNewScene(device);
    scene_ = scene;
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_MEDIUM);

    attachMeshes(device, scene, geometry);
    directSpheres_ = geometry.spheres.size() <= kDirectSphereCount;
    if (!geometry.spheres.empty() && !directSpheres_) {
        RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(geom, unsigned(geometry.spheres.size()));
        rtcSetGeometryUserData(geom, const_cast<SceneGeometry*>(&geometry));
        rtcSetGeometryBoundsFunction(geom, sphereBoundsFn, const_cast<SceneGeometry*>(&geometry));
        rtcSetGeometryIntersectFunction(geom, sphereIntersectFn);
        rtcSetGeometryOccludedFunction(geom, sphereOccludedFn);
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(scene, geom, geometry.sphereGeomId());
        rtcReleaseGeometry(geom);
    }
    // Memory of the structure itself, as for our own (accel.h: excluding the scene's vertex data):
    // the bytes Embree's allocator still holds after the build minus those it held before, seen
    // through its memory monitor (temporary build memory is freed by then).
    // The monitor runs on Embree's build threads. Release increments and the acquire load below
    // order every one of them before this thread reuses the counter's stack slot: Embree's own
    // join inside rtcCommitScene does too, but in uninstrumented code TSan cannot see.
    std::atomic<int64_t> liveBytes{0};
    rtcSetDeviceMemoryMonitorFunction(
        device,
        [](void* user, ssize_t bytes, bool) {
            static_cast<std::atomic<int64_t>*>(user)->fetch_add(int64_t(bytes), std::memory_order_acq_rel);
            return true;
        },
        &liveBytes);
    // Instances: each prototype used is a scene of its own (object space, meshes attached by their
    // prototype geomId), committed once; each instance an Embree instance geometry of it with the
    // instance's transform, attached at instanceGeomBase() + its index, so the hit's instID names it.
    std::vector<bool> used(geometry.prototypes.size(), false);
    for (const MeshInstance& inst : geometry.instances) used[inst.prototype] = true;
    prototypeScenes_.assign(geometry.prototypes.size(), nullptr);
    int64_t vertexBytes = 0;
    for (size_t p = 0; p < geometry.prototypes.size(); ++p) {
        if (!used[p]) continue;
        RTCScene protoScene = rtcNewScene(device);
        prototypeScenes_[p] = protoScene;
        rtcSetSceneBuildQuality(protoScene, RTC_BUILD_QUALITY_MEDIUM);
        int64_t before = liveBytes.load(std::memory_order_acquire);
        attachMeshes(device, protoScene, geometry.prototypes[p]);
        vertexBytes += liveBytes.load(std::memory_order_acquire) - before;  // Embree's copy of the vertex data
        rtcCommitScene(protoScene);
    }
    for (uint32_t i = 0; i < geometry.instances.size(); ++i) {
        const MeshInstance& inst = geometry.instances[i];
        RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(geom, static_cast<RTCScene>(prototypeScenes_[inst.prototype]));
        rtcSetGeometryTransform(geom, 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, &inst.objectToWorld[0][0]);
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(scene, geom, instanceGeomBase() + i);
        rtcReleaseGeometry(geom);
    }
    rtcCommitScene(scene);
    rtcSetDeviceMemoryMonitorFunction(device, nullptr, nullptr);
    stats_.memoryBytes = size_t(std::max<int64_t>(0, liveBytes.load(std::memory_order_acquire) - vertexBytes));

    bounds_ = geometry.bounds();
    stats_.primitives = geometry.primitiveCount() + geometry.instancedPrimitiveCount();
    stats_.buildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

EmbreeAccel::~EmbreeAccel() {
    if (scene_) rtcReleaseScene(static_cast<RTCScene>(scene_));
    for (void* p : prototypeScenes_)
        if (p) rtcReleaseScene(static_cast<RTCScene>(p));
    if (device_) rtcReleaseDevice(static_cast<RTCDevice>(device_));
}

bool EmbreeAccel::intersect(const Ray& ray, Hit& hit) const { return intersectWith(ray, hit, false); }

bool EmbreeAccel::intersectCoherent(const Ray& ray, Hit& hit) const { return intersectWith(ray, hit, true); }

bool EmbreeAccel::intersectWith(const Ray& ray, Hit& hit, bool coherent) const {
    if (!isTraceableRay(ray)) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    // Embree's own hint, given whenever the caller gives us ours (it documents the flag for ray
    // streams; a single ray's kernel may ignore it).
    if (coherent) context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    RTCRayHit rh;
    fillRay(ray, rh.ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(static_cast<RTCScene>(scene_), &context, &rh);
    if (directSpheres_) {
        // The spheres against the closest triangle hit, as the user geometry's callback would test
        // them (sphereIntersectFn).
        Ray r = ray;
        r.tMax = rh.ray.tfar;
        uint32_t closest = closestSphereInLoop(geometry_, r);
        if (closest != kInvalidId) {
            hit.geomId = geometry_.sphereGeomId();
            hit.primId = closest;
            hit.instId = kInvalidId;
            sphereHitRecord(geometry_, ray, closest, r.tMax, hit);
            return true;
        }
    }
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    hit.t = rh.ray.tfar;
    hit.u = rh.hit.u;
    hit.v = rh.hit.v;
    hit.geomId = rh.hit.geomID;
    hit.primId = rh.hit.primID;
    hit.instId = rh.hit.instID[0] == RTC_INVALID_GEOMETRY_ID ? kInvalidId : rh.hit.instID[0] - instanceGeomBase();
    if (const TriangleMesh* mesh = geometry_.meshOf(hit.geomId, hit.instId)) {
        // Recompute the normal from the vertices, exactly as every other backend does, so records
        // compare bit for bit and orientation follows our winding convention.
        const glm::uvec3& tri = mesh->triangles[hit.primId];
        const Vec3f &p0 = mesh->positions[tri.x], &p1 = mesh->positions[tri.y], &p2 = mesh->positions[tri.z];
        hit.ng = glm::normalize(glm::cross(p1 - p0, p2 - p0));
        if (hit.instId != kInvalidId) hit.ng = instanceNormalToWorld(geometry_.instances[hit.instId], hit.ng);
    } else {
        sphereHitRecord(geometry_, ray, hit.primId, hit.t, hit);  // the one user geometry: spheres
    }
    return true;
}

bool EmbreeAccel::occluded(const Ray& ray) const {
    if (!isTraceableRay(ray)) return false;
    if (directSpheres_ && anySphereInLoopOccludes(geometry_, ray)) return true;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay r;
    fillRay(ray, r);
    rtcOccluded1(static_cast<RTCScene>(scene_), &context, &r);
    return r.tfar < 0.f;
}

}  // namespace tessera
