#include "scene/scene.h"

#include <algorithm>

#include "geometry/instances.h"
#include "geometry/intersect.h"
#include "materials/bsdf.h"

namespace tessera {

void Scene::finalize() {
    lights_.build(geometry, materials, pointLights, spotLights, directionalLights, environment ? &*environment : nullptr);
    hasVolumes_ = std::any_of(materials.begin(), materials.end(),
                              [](const Material& m) { return !m.bsdf.thinWalled && !isBlack(m.bsdf.attenuationCoeff); });
}

Scene::Scene(Scene&& o) noexcept
    : geometry(std::move(o.geometry)), materials(std::move(o.materials)), images(std::move(o.images)), pointLights(std::move(o.pointLights)),
      spotLights(std::move(o.spotLights)), directionalLights(std::move(o.directionalLights)), environment(std::move(o.environment)), camera(std::move(o.camera)), cameras(std::move(o.cameras)),
      settings(std::move(o.settings)), sourcePath(std::move(o.sourcePath)), lights_(std::move(o.lights_)),
      hasVolumes_(o.hasVolumes_) {
    lights_.rebind(geometry);
}

Scene& Scene::operator=(Scene&& o) noexcept {
    geometry = std::move(o.geometry);
    materials = std::move(o.materials);
    images = std::move(o.images);
    pointLights = std::move(o.pointLights);
    spotLights = std::move(o.spotLights);
    directionalLights = std::move(o.directionalLights);
    environment = std::move(o.environment);
    camera = std::move(o.camera);
    cameras = std::move(o.cameras);
    settings = std::move(o.settings);
    sourcePath = std::move(o.sourcePath);
    lights_ = std::move(o.lights_);
    hasVolumes_ = o.hasVolumes_;
    lights_.rebind(geometry);
    return *this;
}

namespace {

/// A texture value as a factor in [0, 1]; NaN (a float image may hold one) reads as 0.
float unitRange(float x) { return x >= 0.f ? std::min(x, 1.f) : 0.f; }
Rgb unitRange(const Vec4f& c) { return Rgb(unitRange(c.r), unitRange(c.g), unitRange(c.b)); }

/// uv units per world unit on triangle `primId` for TEXCOORD_`set`: √(uv area / world area), the
/// texel-density term of ray-cone texture LOD (Akenine-Möller et al. 2019, "Texture Level of Detail
/// Strategies for Real-Time Ray Tracing", Ray Tracing Gems ch. 20, eq. 20.4, without its
/// resolution factor: sampleTexture applies the image's size).
/// `inst`: the instance placing the mesh (null for a flat mesh), whose transform scales the area.
float uvPerWorld(const TriangleMesh& mesh, const MeshInstance* inst, int set, uint32_t primId) {
    const glm::uvec3& t = mesh.triangles[primId];
    const std::vector<Vec2f>& uv = mesh.texcoords[set];
    if (uv.empty()) return 0.f;
    Vec2f a = uv[t.y] - uv[t.x], b = uv[t.z] - uv[t.x];
    float uvArea = std::abs(a.x * b.y - a.y * b.x);
    Vec3f p0 = mesh.positions[t.x], p1 = mesh.positions[t.y], p2 = mesh.positions[t.z];
    if (inst) p0 = instancePointToWorld(*inst, p0), p1 = instancePointToWorld(*inst, p1), p2 = instancePointToWorld(*inst, p2);
    float worldArea = glm::length(glm::cross(p1 - p0, p2 - p0));
    float density = worldArea > 0.f ? std::sqrt(uvArea / worldArea) : 0.f;
    return std::isfinite(density) ? density : 0.f;
}

/// glTF normal mapping (2.0 spec, 3.9.3): n = normalize((2·tex − 1) · (scale, scale, 1)) in the
/// tangent frame (T, B = w · (N × T), N) of the interpolated shading normal `n`. Normal maps are
/// read at the finest MIP level: averaging normals shortens and flattens them, and pixel
/// supersampling already filters the shading. Returns `n` where the frame is degenerate.
/// `inst`: the instance placing the mesh (null for a flat mesh); its vertex tangents are taken to
/// world space before they are interpolated, as a flattened copy's are.
Vec3f normalMapped(const TriangleMesh& mesh, const MeshInstance* inst, const TextureRef& tex, float scale, uint32_t primId, float u,
                   float v, const Vec3f& n) {
    const glm::uvec3& t = mesh.triangles[primId];
    auto tangent4 = [&](uint32_t i) { return inst ? instanceTangentToWorld(*inst, mesh.tangents[i]) : mesh.tangents[i]; };
    Vec4f t4 = (1.f - u - v) * tangent4(t.x) + u * tangent4(t.y) + v * tangent4(t.z);
    Vec3f tangent = Vec3f(t4) - glm::dot(n, Vec3f(t4)) * n;  // Gram–Schmidt against the interpolated normal
    float len2 = glm::dot(tangent, tangent);
    if (!(len2 > 1e-12f) || !std::isfinite(len2)) return n;
    tangent /= std::sqrt(len2);
    Vec3f bitangent = (t4.w < 0.f ? -1.f : 1.f) * glm::cross(n, tangent);
    Vec4f c = sampleTexture(tex, mesh.texcoordAt(tex.texCoord, primId, u, v), 0.f);
    Vec3f local((2.f * c.r - 1.f) * scale, (2.f * c.g - 1.f) * scale, 2.f * c.b - 1.f);
    Vec3f m = local.x * tangent + local.y * bitangent + local.z * n;
    float m2 = glm::dot(m, m);
    if (!(m2 > 0.f) || !std::isfinite(m2)) return n;
    return m / std::sqrt(m2);
}

}  // namespace

SurfaceInteraction Scene::interaction(const Ray& ray, const Hit& hit) const {
    SurfaceInteraction si;
    si.ng = hit.ng;
    si.geomId = hit.geomId;
    si.instId = hit.instId;
    si.primId = hit.primId;
    si.bary = Vec2f(hit.u, hit.v);
    if (const TriangleMesh* meshPtr = geometry.meshOf(hit.geomId, hit.instId)) {
        // An instance's mesh is in object space: the point and the normals are interpolated (and
        // normal-mapped) there, then taken to world space; hit.ng is in world space already.
        const MeshInstance* inst = hit.instId != kInvalidId ? &geometry.instances[hit.instId] : nullptr;
        const TriangleMesh& mesh = *meshPtr;
        const glm::uvec3& t = mesh.triangles[hit.primId];
        float b0 = 1.f - hit.u - hit.v;
        si.p = b0 * mesh.positions[t.x] + hit.u * mesh.positions[t.y] + hit.v * mesh.positions[t.z];
        if (inst) si.p = instancePointToWorld(*inst, si.p);
        si.materialId = mesh.materialId;
        si.ns = si.ng;
        if (!mesh.normals.empty()) {
            // An instance's vertex normals go to world space before they are interpolated, as a
            // flattened copy's are, so both shade alike under non-uniform scale.
            auto normal = [&](uint32_t i) { return inst ? instanceNormalToWorld(*inst, mesh.normals[i]) : mesh.normals[i]; };
            Vec3f n = b0 * normal(t.x) + hit.u * normal(t.y) + hit.v * normal(t.z);
            float len2 = glm::dot(n, n);
            if (len2 > 0.f && std::isfinite(len2)) {
                n /= std::sqrt(len2);
                float side = glm::dot(n, si.ng) < 0.f ? -1.f : 1.f;
                si.ns = side * n;
                const MaterialTextures& tex = materials[mesh.materialId].textures;
                if (tex.normal.valid() && !mesh.tangents.empty()) {
                    // Mapped in the file's frame, then put on ng's side as the interpolated normal
                    // is; a mapped normal below the geometric surface keeps the interpolated one.
                    Vec3f mapped = side * normalMapped(mesh, inst, tex.normal, tex.normalScale, hit.primId, hit.u, hit.v, n);
                    if (glm::dot(mapped, si.ng) > 0.f) si.ns = mapped;
                }
            }
        }
    } else {
        const Sphere& s = geometry.spheres[hit.primId];
        si.p = sphereSurfacePoint(s.center, s.radius, ray.o + hit.t * ray.d);
        si.materialId = s.materialId;
        si.ns = si.ng;
    }
    // Instanced meshes never emit: the loader keeps emissive meshes flat (per world triangle lights).
    si.lightIndex = hit.instId == kInvalidId ? lights_.lightIndexOf(hit.geomId, hit.primId) : kInvalidId;
    return si;
}

BsdfParams Scene::bsdfParams(const SurfaceInteraction& si, float footprintW) const {
    const Material& m = materials[si.materialId];
    const TriangleMesh* meshPtr = geometry.meshOf(si.geomId, si.instId);
    if (!m.textures.any() || !meshPtr) return m.bsdf;
    const TriangleMesh& mesh = *meshPtr;
    const MeshInstance* inst = si.instId != kInvalidId ? &geometry.instances[si.instId] : nullptr;
    auto lookup = [&](const TextureRef& tex) {
        float footprintUv = footprintW > 0.f ? footprintW * uvPerWorld(mesh, inst, tex.texCoord, si.primId) : 0.f;
        return sampleTexture(tex, mesh.texcoordAt(tex.texCoord, si.primId, si.bary.x, si.bary.y), footprintUv);
    };
    // glTF 2.0 (3.9.2, and the KHR_materials_* texture definitions): each texture multiplies its factor.
    BsdfParams p = m.bsdf;
    const MaterialTextures& t = m.textures;
    if (t.baseColor.valid()) p.baseColor *= unitRange(lookup(t.baseColor));
    if (t.metallicRoughness.valid()) {
        Vec4f mr = lookup(t.metallicRoughness);  // B = metallic, G = roughness
        p.metallic *= unitRange(mr.b);
        float roughness = std::sqrt(p.alpha) * unitRange(mr.g);
        p.alpha = roughness * roughness;
    }
    if (t.transmission.valid()) p.transmission *= unitRange(lookup(t.transmission).r);
    if (t.specular.valid()) p.specular *= unitRange(lookup(t.specular).a);
    if (t.specularColor.valid()) p.specularColor *= unitRange(lookup(t.specularColor));
    finalizeBsdfParams(p);
    return p;
}

}  // namespace tessera
