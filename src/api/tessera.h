#pragma once
/// \file tessera.h
/// Tessera's public library interface, installed as <tessera/tessera.h> and linked as Tessera::core
/// (`find_package(Tessera)`). It exists for one job: letting users build our acceleration structures
/// (or Embree) over their meshes, and validate *their own* ray–scene intersection code hit for hit
/// against Embree in their tests, with the same ray sets and the same tie classification as
/// `tessera validate-accel`. Only standard-library types appear here, so a consumer needs no glm,
/// TBB, Embree or OIIO headers; everything else stays inside the shared library.
///
/// Hit-record conventions (Embree's, which every structure must reproduce):
///  - t is measured along the unnormalised ray direction, valid in the open interval (tMin, tMax);
///  - triangles: (u, v) are the barycentric weights of vertices 1 and 2, ng = normalize((p1−p0)×(p2−p0));
///  - spheres: (u, v) = (φ/2π, θ/π), ng = the outward unit normal;
///  - geomId: mesh i has geomId i in the order added; all spheres together form geometry
///    `meshCount()` with primId = sphere index.
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#if defined(TESSERA_API_BUILD)
#define TESSERA_API __attribute__((visibility("default")))
#else
#define TESSERA_API
#endif

namespace tessera::api {

inline constexpr uint32_t kInvalidId = 0xffffffffu;

struct Ray {
    std::array<float, 3> origin{0.f, 0.f, 0.f};
    std::array<float, 3> direction{0.f, 0.f, 1.f};
    float tMin = 0.f;
    float tMax = std::numeric_limits<float>::infinity();
};

struct Hit {
    float t = std::numeric_limits<float>::infinity();
    float u = 0.f, v = 0.f;
    uint32_t primId = kInvalidId;
    uint32_t geomId = kInvalidId;
    std::array<float, 3> ng{0.f, 0.f, 0.f};
};

/// World-space geometry: triangle meshes and analytic spheres. Copyable; structures built over it
/// keep their own reference, so it must outlive them.
class TESSERA_API Geometry {
public:
    Geometry();
    ~Geometry();
    Geometry(Geometry&&) noexcept;
    Geometry& operator=(Geometry&&) noexcept;
    Geometry(const Geometry&) = delete;
    Geometry& operator=(const Geometry&) = delete;

    /// Loads a glTF scene (.gltf/.glb), PLY (also .ply.gz) or OBJ file. Throws std::runtime_error
    /// naming the file, the element and the problem on malformed input.
    static Geometry load(const std::string& path);

    /// Adds a mesh: `positions` holds x, y, z per vertex, `indices` three vertex indices per triangle.
    /// Returns its geomId. Throws std::invalid_argument on sizes that are not multiples of 3 or
    /// indices out of range. Degenerate triangles are kept (structures must cope with them).
    uint32_t addTriangleMesh(const std::vector<float>& positions, const std::vector<uint32_t>& indices);
    /// Adds an analytic sphere; returns its primId within the sphere geometry.
    uint32_t addSphere(std::array<float, 3> center, float radius);

    size_t meshCount() const;
    size_t sphereCount() const;
    size_t primitiveCount() const;
    /// Lower and upper corners of the bounding box of everything.
    std::array<float, 6> bounds() const;

    struct Impl;
    Impl& impl() const { return *impl_; }

private:
    std::unique_ptr<Impl> impl_;
};

/// Names of the built-in structures: "embree", "bvh", "brute", and any added since.
TESSERA_API std::vector<std::string> accelNames();

/// One of Tessera's acceleration structures, built over a Geometry that must outlive it.
class TESSERA_API Structure {
public:
    /// Throws std::invalid_argument for an unknown name. threads = 0 uses every core for the build.
    Structure(const Geometry& geometry, std::string_view name = "embree", int threads = 0);
    ~Structure();
    Structure(Structure&&) noexcept;
    Structure& operator=(Structure&&) noexcept;

    std::string name() const;
    double buildSeconds() const;
    size_t memoryBytes() const;

    /// Closest hit in (tMin, tMax); false (and `hit` untouched) on a miss. Thread-safe. Rays with a
    /// non-finite or zero direction never hit.
    bool intersect(const Ray& ray, Hit& hit) const;
    /// Any hit in (tMin, tMax). Thread-safe.
    bool occluded(const Ray& ray) const;

    struct Impl;
    Impl& impl() const { return *impl_; }

private:
    std::unique_ptr<Impl> impl_;
};

/// A user's closest-hit query: must follow the conventions above and be safe to call from several
/// threads at once (or set ValidationOptions::threads = 1).
using IntersectFn = std::function<bool(const Ray&, Hit&)>;
/// A user's any-hit query; when empty, validation derives it from the closest hit.
using OccludedFn = std::function<bool(const Ray&)>;

struct ValidationOptions {
    /// Any of "primary", "random", "diffuse", "grazing", "shadow" (see `tessera validate-accel --help`).
    std::vector<std::string> kinds{"primary", "random", "diffuse", "grazing"};
    size_t rays = 1000000;  ///< in all, split evenly over the kinds
    uint64_t seed = 1;
    int threads = 0;        ///< 0 = all cores
    float tRelative = 1e-5f;  ///< |Δt| ≤ tRelative·t on the same primitive
    float uv = 1e-4f;         ///< |Δu|, |Δv| on the same triangle
    float normalCos = 0.9999f;
    size_t maxExamples = 20;
};

struct ValidationExample {
    std::string kind;
    size_t rayIndex = 0;
    Ray ray;
    bool testHit = false, referenceHit = false;
    Hit test, reference;
    std::string reason;
};

struct TESSERA_API ValidationReport {
    size_t rays = 0, agreements = 0, ties = 0, errors = 0;
    std::vector<ValidationExample> examples;  ///< the first errors, in ray order per kind
    /// The same JSON object `tessera validate-accel --json` prints.
    std::string json() const;
};

/// Casts the rays through `test` and through Embree and classifies every ray as an agreement, an
/// admissible tie (edge/vertex/duplicate/silhouette, confirmed in double precision) or an error.
/// Deterministic for a given seed.
TESSERA_API ValidationReport validate(const Geometry& geometry, const IntersectFn& test,
                                      const OccludedFn& testOccluded = {}, const ValidationOptions& options = {});
TESSERA_API ValidationReport validate(const Geometry& geometry, const Structure& test,
                                      const ValidationOptions& options = {});

/// The rays validation uses, for users who want to drive their own comparisons.
TESSERA_API std::vector<Ray> generateRays(const Geometry& geometry, std::string_view kind, size_t count,
                                          uint64_t seed);

/// The library's version and git revision, e.g. "0.1.0 (abc1234)".
TESSERA_API std::string version();

}  // namespace tessera::api
