#include "scene/scene.h"

#include "geometry/intersect.h"

namespace tessera {

void Scene::finalize() {
    lights_.build(geometry, materials, pointLights, spotLights, directionalLights, environment ? &*environment : nullptr);
}

Scene::Scene(Scene&& o) noexcept
    : geometry(std::move(o.geometry)), materials(std::move(o.materials)), images(std::move(o.images)), pointLights(std::move(o.pointLights)),
      spotLights(std::move(o.spotLights)), directionalLights(std::move(o.directionalLights)), environment(std::move(o.environment)), camera(std::move(o.camera)),
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
    settings = std::move(o.settings);
    sourcePath = std::move(o.sourcePath);
    lights_ = std::move(o.lights_);
    lights_.rebind(geometry);
    return *this;
}

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
                si.ns = glm::dot(n, si.ng) < 0.f ? -n : n;
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

}  // namespace tessera
