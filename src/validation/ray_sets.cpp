#include "validation/ray_sets.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/frame.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "geometry/instances.h"
#include "geometry/intersect.h"

namespace tessera {
namespace {

/// A scene box that is never empty or flat, so origins and cameras can be placed around it.
Bounds3f usableBounds(const SceneGeometry& g) {
    Bounds3f b = g.bounds();
    if (b.empty() || !isFinite(b.lower) || !isFinite(b.upper)) {
        b.lower = Vec3f(-1.f);
        b.upper = Vec3f(1.f);
    }
    float pad = 1e-3f * std::max(1e-3f, maxComponent(b.upper - b.lower));
    b.lower -= Vec3f(pad);
    b.upper += Vec3f(pad);
    return b;
}

Vec3f randomPoint(Pcg32& rng, const Bounds3f& b) {
    return b.lower + (b.upper - b.lower) * Vec3f(rng.nextFloat(), rng.nextFloat(), rng.nextFloat());
}

/// The surface point of a hit, reconstructed from the primitive (as Scene::interaction does).
Vec3f hitPoint(const SceneGeometry& g, const Ray& ray, const Hit& h) {
    if (const TriangleMesh* m = g.meshOf(h.geomId, h.instId)) {
        const glm::uvec3& t = m->triangles[h.primId];
        Vec3f p = (1.f - h.u - h.v) * m->positions[t.x] + h.u * m->positions[t.y] + h.v * m->positions[t.z];
        return h.instId != kInvalidId ? instancePointToWorld(g.instances[h.instId], p) : p;  // an instance's mesh is in object space
    }
    const Sphere& s = g.spheres[h.primId];
    return sphereSurfacePoint(s.center, s.radius, ray.o + h.t * ray.d);
}

/// Ray `i` of a square image in pixel order (wrapping around for more rays than pixels), jittered.
Ray primaryRay(const Camera& cam, size_t i, Pcg32& rng) {
    size_t w = size_t(cam.width());
    Vec2f raster(float(i % w) + rng.nextFloat(), float((i / w) % size_t(cam.height())) + rng.nextFloat());
    return cam.generateRay(raster, Vec2f(0.5f));
}

/// A square image of about `count` pixels through the scene's camera or one framing the bounds.
Camera makeCamera(const Bounds3f& b, const std::optional<CameraDesc>& camera, size_t count) {
    int side = std::max(1, int(std::ceil(std::sqrt(double(count)))));
    return Camera(camera ? *camera : framingCamera(b), side, side);
}

std::vector<Ray> primaryRays(const Bounds3f& b, const std::optional<CameraDesc>& camera, size_t count, Pcg32& rng) {
    std::vector<Ray> rays;
    rays.reserve(count);
    Camera cam = makeCamera(b, camera, count);
    for (size_t i = 0; i < count; ++i) rays.push_back(primaryRay(cam, i, rng));
    return rays;
}

std::vector<Ray> randomRays(const Bounds3f& b, size_t count, Pcg32& rng) {
    std::vector<Ray> rays;
    rays.reserve(count);
    Vec3f ext = b.upper - b.lower;
    float diag = glm::length(ext);
    for (size_t i = 0; i < count; ++i) {
        Ray r;
        r.o = b.lower - 0.25f * ext + 1.5f * ext * Vec3f(rng.nextFloat(), rng.nextFloat(), rng.nextFloat());
        uint32_t variant = rng.nextU32() % 8;
        if (variant < 3) {
            r.d = glm::normalize(randomPoint(rng, b) - r.o);
        } else if (variant == 3) {
            // Axis-aligned, with signed zeros: the octant must come from the sign bit.
            uint32_t axis = rng.nextU32() % 3, signs = rng.nextU32();
            for (int a = 0; a < 3; ++a) r.d[a] = (signs >> a & 1) ? -0.f : 0.f;
            r.d[axis] = (signs >> 3 & 1) ? -1.f : 1.f;
        } else {
            r.d = sampleUniformSphere(rng.next2D());
        }
        if (variant == 7) r.tMin = 0.5f * diag * rng.nextFloat();  // a clipped start
        if (rng.nextU32() % 8 == 0) r.tMax = diag * rng.nextFloat();  // a clipped end
        if (rng.nextU32() % 4 == 0) r.d *= 0.01f + 10.f * rng.nextFloat();  // not unit length
        rays.push_back(r);
    }
    return rays;
}

/// Diffuse or shadow rays from the reference's primary hits, at most `count`: a diffuse ray bounces
/// cosine-distributed; a shadow ray ends at a random point on the top face of the bounds, the
/// geometry's "sky". Diffuse rays come out shuffled, so that consecutive ones are as incoherent as
/// a renderer's second bounce.
std::vector<Ray> raysFromSurfaces(const SceneGeometry& g, const Accel& reference, RayKind kind, const Bounds3f& b,
                                  const std::optional<CameraDesc>& camera, size_t count, Pcg32& rng) {
    std::vector<Ray> rays;
    rays.reserve(count);
    Camera cam = makeCamera(b, camera, count);
    size_t attempts = 0;
    while (rays.size() < count && attempts < 4 * count + 64) {
        Ray pr = primaryRay(cam, attempts++, rng);
        Hit h;
        if (!reference.intersect(pr, h)) continue;
        Vec3f p = hitPoint(g, pr, h);
        Vec3f n = glm::dot(h.ng, pr.d) < 0.f ? h.ng : -h.ng;
        if (kind == RayKind::Diffuse) {
            rays.push_back(spawnRay(p, n, Frame(n).toWorld(sampleCosineHemisphere(rng.next2D()))));
        } else {
            Vec3f target(b.lower.x + rng.nextFloat() * (b.upper.x - b.lower.x), b.upper.y,
                         b.lower.z + rng.nextFloat() * (b.upper.z - b.lower.z));
            rays.push_back(spawnShadowRay(p, n, target, Vec3f(0.f)));
        }
    }
    if (kind == RayKind::Diffuse)
        for (size_t i = rays.size(); i > 1; --i) std::swap(rays[i - 1], rays[rng.nextU32() % i]);
    return rays;
}

/// A point on an edge or a vertex of a triangle, or on a sphere's surface, with the surface normal
/// and a tangent there (unnormalised).
void grazingTarget(const SceneGeometry& g, size_t pick, size_t triCount, Pcg32& rng, Vec3f& target, Vec3f& tangent,
                   Vec3f& normal) {
    if (pick < triCount) {
        uint32_t gi = 0;
        while (pick >= g.meshes[gi].triangles.size()) pick -= g.meshes[gi++].triangles.size();
        const TriangleMesh& m = g.meshes[gi];
        const glm::uvec3& t = m.triangles[pick];
        Vec3f p[3] = {m.positions[t.x], m.positions[t.y], m.positions[t.z]};
        int e = int(rng.nextU32() % 3);
        float w = (rng.nextU32() % 4 == 0) ? 0.f : rng.nextFloat();  // a vertex or a point on an edge
        target = p[e] + w * (p[(e + 1) % 3] - p[e]);
        normal = glm::cross(p[1] - p[0], p[2] - p[0]);
        tangent = p[(e + 1) % 3] - p[e];
    } else {
        const Sphere& s = g.spheres[pick - triCount];
        normal = sampleUniformSphere(rng.next2D());
        target = s.center + s.radius * normal;
        tangent = glm::cross(normal, sampleUniformSphere(rng.next2D()));
    }
}

std::vector<Ray> grazingRays(const SceneGeometry& g, const Bounds3f& b, size_t count, Pcg32& rng) {
    std::vector<Ray> rays;
    rays.reserve(count);
    float diag = glm::length(b.upper - b.lower);
    size_t triCount = 0;
    for (const TriangleMesh& m : g.meshes) triCount += m.triangles.size();
    size_t prims = triCount + g.spheres.size();
    for (size_t i = 0; i < count; ++i) {
        Ray r;
        if (prims == 0) {
            r.o = randomPoint(rng, b);
            r.d = sampleUniformSphere(rng.next2D());
            rays.push_back(r);
            continue;
        }
        Vec3f target, tangent, normal;
        grazingTarget(g, size_t(rng.nextU32()) % prims, triCount, rng, target, tangent, normal);
        float nLen = glm::length(normal), tLen = glm::length(tangent);
        if (rng.nextU32() % 2 == 0 && nLen > 0.f && tLen > 0.f && std::isfinite(nLen)) {
            // Nearly tangent: mostly along the surface, a little across it.
            Vec3f side = glm::cross(normal / nLen, tangent / tLen);
            Vec3f inPlane = glm::normalize(tangent / tLen * (rng.nextFloat() - 0.5f) + side * (rng.nextFloat() - 0.5f) + Vec3f(1e-20f));
            r.d = glm::normalize(inPlane + (rng.nextFloat() - 0.5f) * 2e-3f * normal / nLen);
        } else {
            r.d = sampleUniformSphere(rng.next2D());
        }
        if (!isFinite(r.d)) r.d = sampleUniformSphere(rng.next2D());
        r.o = target - r.d * (diag * (0.05f + rng.nextFloat()));
        rays.push_back(r);
    }
    return rays;
}

}  // namespace

std::string_view toString(RayKind kind) {
    switch (kind) {
        case RayKind::Primary: return "primary";
        case RayKind::Random: return "random";
        case RayKind::Diffuse: return "diffuse";
        case RayKind::Grazing: return "grazing";
        case RayKind::Shadow: return "shadow";
    }
    return "?";
}

RayKind parseRayKind(std::string_view name) {
    for (RayKind k : {RayKind::Primary, RayKind::Random, RayKind::Diffuse, RayKind::Grazing, RayKind::Shadow})
        if (toString(k) == name) return k;
    throw InputError("unknown ray kind '" + std::string(name) + "' (known: primary, random, diffuse, grazing, shadow)");
}

CameraDesc framingCamera(const Bounds3f& b) {
    CameraDesc desc;
    Vec3f center = b.center();
    float radius = 0.5f * glm::length(b.upper - b.lower);
    desc.yfov = 0.7f;
    float distance = radius / std::sin(0.5f * desc.yfov) * 1.05f;
    Vec3f eye = center + distance * glm::normalize(Vec3f(0.35f, 0.3f, 1.f));
    desc.cameraToWorld = glm::inverse(glm::lookAt(eye, center, Vec3f(0, 1, 0)));
    desc.znear = std::max(1e-4f, 1e-3f * radius);
    return desc;
}

std::vector<Ray> generateRays(const SceneGeometry& g, const Accel& reference, RayKind kind, size_t count,
                              uint64_t seed, const std::optional<CameraDesc>& camera) {
    Bounds3f b = usableBounds(g);
    Pcg32 rng(hashCombine(seed, uint64_t(kind)), 0);
    switch (kind) {
        case RayKind::Primary: return primaryRays(b, camera, count, rng);
        case RayKind::Random: return randomRays(b, count, rng);
        case RayKind::Grazing: return grazingRays(g, b, count, rng);
        case RayKind::Diffuse:
        case RayKind::Shadow: {
            std::vector<Ray> rays = raysFromSurfaces(g, reference, kind, b, camera, count, rng);
            // A scene the camera barely sees: fill up with random rays.
            if (rays.size() < count) {
                std::vector<Ray> more = generateRays(g, reference, RayKind::Random, count - rays.size(), seed + 1, camera);
                rays.insert(rays.end(), more.begin(), more.end());
            }
            return rays;
        }
    }
    return {};
}

}  // namespace tessera
