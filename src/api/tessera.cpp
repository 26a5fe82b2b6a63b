/// \file tessera.cpp
/// The public library (<tessera/tessera.h>): thin adapters from the standard-library types of the
/// public header to the internal geometry, Accel and validation code. Nothing here is on a hot path
/// except the per-ray conversions, which are a handful of copies.
#include "api/tessera.h"

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <optional>
#include <stdexcept>

#include "accel/accel.h"
#include "validation/validate.h"
#include "core/error.h"
#include "core/version.h"
#include "scene/scene_loader.h"

namespace tessera::api {

struct Geometry::Impl {
    SceneGeometry geometry;
    std::optional<CameraDesc> camera;  ///< a loaded glTF scene's camera, used for primary rays
};

struct Structure::Impl {
    std::unique_ptr<Accel> accel;
};

namespace {

tessera::Ray toInternal(const Ray& r) {
    tessera::Ray out;
    out.o = Vec3f(r.origin[0], r.origin[1], r.origin[2]);
    out.d = Vec3f(r.direction[0], r.direction[1], r.direction[2]);
    out.tMin = r.tMin;
    out.tMax = r.tMax;
    return out;
}

Ray toPublic(const tessera::Ray& r) {
    return {{r.o.x, r.o.y, r.o.z}, {r.d.x, r.d.y, r.d.z}, r.tMin, r.tMax};
}

Hit toPublic(const tessera::Hit& h) {
    return {h.t, h.u, h.v, h.primId, h.geomId, {h.ng.x, h.ng.y, h.ng.z}};
}

tessera::Hit toInternal(const Hit& h) {
    tessera::Hit out;
    out.t = h.t;
    out.u = h.u;
    out.v = h.v;
    out.primId = h.primId;
    out.geomId = h.geomId;
    out.ng = Vec3f(h.ng[0], h.ng[1], h.ng[2]);
    return out;
}

/// A user's intersection code behind the internal Accel interface, so the validation routine treats
/// it exactly like one of our structures.
class CallbackAccel final : public Accel {
public:
    CallbackAccel(const SceneGeometry& g, const IntersectFn& closest, const OccludedFn& any)
        : bounds_(g.bounds()), closest_(closest), any_(any) {}
    std::string_view name() const override { return "user"; }
    bool intersect(const tessera::Ray& ray, tessera::Hit& hit) const override {
        Hit h;
        if (!closest_(toPublic(ray), h)) return false;
        hit = toInternal(h);
        return true;
    }
    bool occluded(const tessera::Ray& ray) const override {
        if (any_) return any_(toPublic(ray));
        Hit h;
        return closest_(toPublic(ray), h);
    }
    Bounds3f bounds() const override { return bounds_; }
    AccelStats stats() const override { return {}; }

private:
    Bounds3f bounds_;
    const IntersectFn& closest_;
    const OccludedFn& any_;
};

ValidationReport toPublic(const ValidationResult& r) {
    ValidationReport out;
    out.rays = r.rays;
    out.agreements = r.agreements;
    out.ties = r.ties;
    out.errors = r.errors;
    for (const tessera::ValidationExample& e : r.examples)
        out.examples.push_back({std::string(toString(e.kind)), e.rayIndex, toPublic(e.ray), e.testHit, e.refHit,
                                toPublic(e.test), toPublic(e.ref), e.reason});
    return out;
}

ValidationReport runValidation(const Geometry::Impl& g, const Accel& test, const ValidationOptions& opt) {
    if (opt.kinds.empty()) throw std::invalid_argument("tessera::api::validate: no ray kinds given");
    std::vector<RayKind> kinds;
    try {
        for (const std::string& k : opt.kinds) kinds.push_back(parseRayKind(k));
    } catch (const InputError& e) {
        throw std::invalid_argument(std::string("tessera::api::validate: ") + e.what());
    }
    ValidationTolerances tol;
    tol.tRelative = opt.tRelative;
    tol.uv = opt.uv;
    tol.normalCos = opt.normalCos;
    int threads = opt.threads > 0 ? opt.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(threads);
    ValidationResult total;
    arena.execute([&] {
        AccelOptions ao;
        ao.threads = threads;
        auto reference = createAccel("embree", g.geometry, ao);
        for (size_t k = 0; k < kinds.size(); ++k) {
            size_t n = opt.rays / kinds.size() + (k < opt.rays % kinds.size() ? 1 : 0);
            std::vector<tessera::Ray> rays = generateRays(g.geometry, *reference, kinds[k], n, opt.seed, g.camera);
            total.merge(compareAccels(test, *reference, g.geometry, rays, kinds[k], tol, opt.maxExamples),
                        opt.maxExamples);
        }
    });
    return toPublic(total);
}

}  // namespace

// --- Geometry ---------------------------------------------------------------------------------------

Geometry::Geometry() : impl_(std::make_unique<Impl>()) {}
Geometry::~Geometry() = default;
Geometry::Geometry(Geometry&&) noexcept = default;
Geometry& Geometry::operator=(Geometry&&) noexcept = default;

Geometry Geometry::load(const std::string& path) {
    Geometry out;
    std::vector<std::string> warnings;
    // InputError/SceneError derive from std::runtime_error and already name file, element, problem.
    out.impl_->geometry = loadGeometryFile(path, out.impl_->camera, warnings);
    return out;
}

uint32_t Geometry::addTriangleMesh(const std::vector<float>& positions, const std::vector<uint32_t>& indices) {
    if (positions.size() % 3 != 0)
        throw std::invalid_argument("addTriangleMesh: positions.size() must be a multiple of 3");
    if (indices.size() % 3 != 0) throw std::invalid_argument("addTriangleMesh: indices.size() must be a multiple of 3");
    TriangleMesh mesh;
    mesh.name = "mesh " + std::to_string(impl_->geometry.meshes.size());
    size_t vertices = positions.size() / 3;
    for (size_t i = 0; i < vertices; ++i)
        mesh.positions.emplace_back(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]);
    for (size_t i = 0; i < indices.size(); i += 3) {
        for (int k = 0; k < 3; ++k)
            if (indices[i + k] >= vertices)
                throw std::invalid_argument("addTriangleMesh: triangle " + std::to_string(i / 3) + " has index " +
                                            std::to_string(indices[i + k]) + " but there are only " +
                                            std::to_string(vertices) + " vertices");
        mesh.triangles.emplace_back(indices[i], indices[i + 1], indices[i + 2]);
    }
    impl_->geometry.meshes.push_back(std::move(mesh));
    return uint32_t(impl_->geometry.meshes.size() - 1);
}

uint32_t Geometry::addSphere(std::array<float, 3> center, float radius) {
    if (!(radius > 0.f) || !std::isfinite(radius)) throw std::invalid_argument("addSphere: radius must be positive and finite");
    Sphere s;
    s.name = "sphere " + std::to_string(impl_->geometry.spheres.size());
    s.center = Vec3f(center[0], center[1], center[2]);
    s.radius = radius;
    impl_->geometry.spheres.push_back(std::move(s));
    return uint32_t(impl_->geometry.spheres.size() - 1);
}

size_t Geometry::meshCount() const { return impl_->geometry.meshes.size(); }
size_t Geometry::sphereCount() const { return impl_->geometry.spheres.size(); }
size_t Geometry::primitiveCount() const { return impl_->geometry.primitiveCount(); }
std::array<float, 6> Geometry::bounds() const {
    Bounds3f b = impl_->geometry.bounds();
    return {b.lower.x, b.lower.y, b.lower.z, b.upper.x, b.upper.y, b.upper.z};
}

// --- Structure --------------------------------------------------------------------------------------

std::vector<std::string> accelNames() { return tessera::accelNames(); }

Structure::Structure(const Geometry& geometry, std::string_view name, int threads) : impl_(std::make_unique<Impl>()) {
    AccelOptions options;
    options.threads = threads;
    try {
        impl_->accel = createAccel(name, geometry.impl().geometry, options);
    } catch (const InputError& e) {
        throw std::invalid_argument(e.what());
    }
}
Structure::~Structure() = default;
Structure::Structure(Structure&&) noexcept = default;
Structure& Structure::operator=(Structure&&) noexcept = default;

std::string Structure::name() const { return std::string(impl_->accel->name()); }
double Structure::buildSeconds() const { return impl_->accel->stats().buildSeconds; }
size_t Structure::memoryBytes() const { return impl_->accel->stats().memoryBytes; }

bool Structure::intersect(const Ray& ray, Hit& hit) const {
    tessera::Hit h;
    if (!impl_->accel->intersect(toInternal(ray), h)) return false;
    hit = toPublic(h);
    return true;
}
bool Structure::occluded(const Ray& ray) const { return impl_->accel->occluded(toInternal(ray)); }

// --- Validation -------------------------------------------------------------------------------------

std::string ValidationReport::json() const {
    ValidationResult r;
    r.rays = rays;
    r.agreements = agreements;
    r.ties = ties;
    r.errors = errors;
    for (const ValidationExample& e : examples)
        r.examples.push_back({parseRayKind(e.kind), e.rayIndex, toInternal(e.ray), e.testHit, e.referenceHit,
                              toInternal(e.test), toInternal(e.reference), e.reason});
    return toJson(r).dump(2);
}

ValidationReport validate(const Geometry& geometry, const IntersectFn& test, const OccludedFn& testOccluded,
                          const ValidationOptions& options) {
    if (!test) throw std::invalid_argument("tessera::api::validate: no intersection function given");
    CallbackAccel accel(geometry.impl().geometry, test, testOccluded);
    return runValidation(geometry.impl(), accel, options);
}

ValidationReport validate(const Geometry& geometry, const Structure& test, const ValidationOptions& options) {
    return runValidation(geometry.impl(), *test.impl().accel, options);
}

std::vector<Ray> generateRays(const Geometry& geometry, std::string_view kind, size_t count, uint64_t seed) {
    RayKind k;
    try {
        k = parseRayKind(kind);
    } catch (const InputError& e) {
        throw std::invalid_argument(std::string("tessera::api::generateRays: ") + e.what());
    }
    const Geometry::Impl& g = geometry.impl();
    auto reference = createAccel("embree", g.geometry);
    std::vector<Ray> out;
    for (const tessera::Ray& r : tessera::generateRays(g.geometry, *reference, k, count, seed, g.camera))
        out.push_back(toPublic(r));
    return out;
}

std::string version() { return std::string(versionString()) + " (" + gitRevision() + ")"; }

}  // namespace tessera::api
