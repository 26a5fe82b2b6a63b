#include "scene/scene.h"

#include "geometry/intersect.h"
#include "materials/bsdf.h"

namespace tessera {

void Scene::finalize() {
    lights_.build(geometry, materials, pointLights, spotLights, directionalLights, environment ? &*environment : nullptr);
}

Scene::Scene(Scene&& o) noexcept
    : geometry(std::move(o.geometry)), materials(std::move(o.materials)), images(std::move(o.images)), pointLights(std::move(o.pointLights)),
      spotLights(std::move(o.spotLights)), directionalLights(std::move(o.directionalLights)), environment(std::move(o.environment)), camera(std::move(o.camera)), cameras(std::move(o.cameras)),
      settings(std::move(o.settings)), sourcePath(std::move(o.sourcePath)), lights_(std::move(o.lights_)) {
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
float uvPerWorld(const TriangleMesh& mesh, int set, uint32_t primId) {
    const glm::uvec3& t = mesh.triangles[primId];
    const std::vector<Vec2f>& uv = mesh.texcoords[set];
    if (uv.empty()) return 0.f;
    Vec2f a = uv[t.y] - uv[t.x], b = uv[t.z] - uv[t.x];
    float uvArea = std::abs(a.x * b.y - a.y * b.x);
    float worldArea = glm::length(glm::cross(mesh.positions[t.y] - mesh.positions[t.x], mesh.positions[t.z] - mesh.positions[t.x]));
    float density = worldArea > 0.f ? std::sqrt(uvArea / worldArea) : 0.f;
    return std::isfinite(density) ? density : 0.f;
}

/// glTF normal mapping (2.0 spec, 3.9.3): n = normalize((2·tex − 1) · (scale, scale, 1)) in the
/// tangent frame (T, B = w · (N × T), N) of the interpolated shading normal `n`. Normal maps are
/// read at the finest MIP level: averaging normals shortens and flattens them, and pixel
/// supersampling already filters the shading. Returns `n` where the frame is degenerate.
Vec3f normalMapped(const TriangleMesh& mesh, const TextureRef& tex, float scale, uint32_t primId, float u, float v, const Vec3f& n) {
    const glm::uvec3& t = mesh.triangles[primId];
    Vec4f t4 = (1.f - u - v) * mesh.tangents[t.x] + u * mesh.tangents[t.y] + v * mesh.tangents[t.z];
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
    si.primId = hit.primId;
    si.bary = Vec2f(hit.u, hit.v);
    if (hit.geomId < geometry.meshes.size()) {
        const TriangleMesh& mesh = geometry.meshes[hit.geomId];
        const glm::uvec3& t = mesh.triangles[hit.primId];
        float b0 = 1.f - hit.u - hit.v;
        si.p = b0 * mesh.positions[t.x] + hit.u * mesh.positions[t.y] + hit.v * mesh.positions[t.z];
        si.materialId = mesh.materialId;
        si.ns = si.ng;
        if (!mesh.normals.empty()) {
            Vec3f n = b0 * mesh.normals[t.x] + hit.u * mesh.normals[t.y] + hit.v * mesh.normals[t.z];
            float len2 = glm::dot(n, n);
            if (len2 > 0.f && std::isfinite(len2)) {
                n /= std::sqrt(len2);
                float side = glm::dot(n, si.ng) < 0.f ? -1.f : 1.f;
                si.ns = side * n;
                const MaterialTextures& tex = materials[mesh.materialId].textures;
                if (tex.normal.valid() && !mesh.tangents.empty()) {
                    // Mapped in the file's frame, then put on ng's side as the interpolated normal
                    // is; a mapped normal below the geometric surface keeps the interpolated one.
                    Vec3f mapped = side * normalMapped(mesh, tex.normal, tex.normalScale, hit.primId, hit.u, hit.v, n);
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
    si.lightIndex = lights_.lightIndexOf(hit.geomId, hit.primId);
    return si;
}

BsdfParams Scene::bsdfParams(const SurfaceInteraction& si, float footprintW) const {
    const Material& m = materials[si.materialId];
    if (!m.textures.any() || si.geomId >= geometry.meshes.size()) return m.bsdf;
    const TriangleMesh& mesh = geometry.meshes[si.geomId];
    auto lookup = [&](const TextureRef& tex) {
        float footprintUv = footprintW > 0.f ? footprintW * uvPerWorld(mesh, tex.texCoord, si.primId) : 0.f;
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
