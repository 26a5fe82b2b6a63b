#include "scene/tangents.h"

#include <array>
#include <cstring>
#include <unordered_map>

#include "core/fnv1a.h"
#include "core/frame.h"

namespace tessera {
namespace {

/// Vertices MikkTSpace treats as one: equal position, normal and texture coordinate (bit for bit).
using WeldKey = std::array<uint32_t, 8>;
struct WeldKeyHash {
    size_t operator()(const WeldKey& k) const { return size_t(fnv1a64(k.data(), sizeof(WeldKey))); }
};

WeldKey weldKey(const Vec3f& p, const Vec3f& n, const Vec2f& uv) {
    float f[8] = {p.x, p.y, p.z, n.x, n.y, n.z, uv.x, uv.y};
    WeldKey k;
    std::memcpy(k.data(), f, sizeof(f));
    return k;
}

Vec3f projectOntoPlane(const Vec3f& v, const Vec3f& n) { return v - glm::dot(n, v) * n; }

Vec3f normalizedOrZero(const Vec3f& v) {
    float len2 = glm::dot(v, v);
    return len2 > 0.f && std::isfinite(len2) ? v / std::sqrt(len2) : Vec3f(0.f);
}

/// A triangle's texture-space tangent direction: ∂p/∂u, from the edges e1 = p1 − p0, e2 = p2 − p0
/// and their uv differences, ∂p/∂u = (Δv2·e1 − Δv1·e2) / det with det = Δu1·Δv2 − Δu2·Δv1
/// (Mikkelsen 2008, eq. 3.2; the same 2×2 inversion as Lengyel's). Only the direction and the sign
/// of det (whether the uv mapping preserves orientation) matter to MikkTSpace.
struct FaceTangent {
    Vec3f dir{0.f};       ///< unit ∂p/∂u, or zero for a uv- or position-degenerate triangle
    bool orientationKnown = false;
    bool preservesOrientation = true;  ///< det > 0: the bitangent sign is +1
};

FaceTangent faceTangent(const Vec3f p[3], const Vec2f uv[3]) {
    Vec3f e1 = p[1] - p[0], e2 = p[2] - p[0];
    // glTF's v runs down the image, MikkTSpace's (Blender's, where it is the standard) up, and
    // normal maps' +Y points up the image: tangents are computed on (u, 1 − v), as exporters write
    // them (Khronos glTF-Sample-Models issue 174). ∂p/∂u is the same either way; the orientation
    // flips, so B = w · (N × T) points up the image (along −∂p/∂v in glTF's uv).
    Vec2f d1 = uv[1] - uv[0], d2 = uv[2] - uv[0];
    d1.y = -d1.y;
    d2.y = -d2.y;
    float det = d1.x * d2.y - d2.x * d1.y;
    FaceTangent f;
    if (!(det != 0.f) || !std::isfinite(det)) return f;
    f.orientationKnown = true;
    f.preservesOrientation = det > 0.f;
    f.dir = normalizedOrZero((d2.y * e1 - d1.y * e2) * (det > 0.f ? 1.f : -1.f));
    return f;
}

}  // namespace

size_t generateMikkTangents(TriangleMesh& mesh, int uvSet) {
    const std::vector<Vec2f>& uvs = mesh.texcoords[uvSet];
    const size_t vertexCount = mesh.positions.size();
    if (mesh.normals.size() != vertexCount || uvs.size() != vertexCount) return 0;

    // 1. Weld: corners at equal (position, normal, uv) share a tangent whatever their index.
    std::vector<uint32_t> canon(vertexCount);
    std::unordered_map<WeldKey, uint32_t, WeldKeyHash> welded;
    welded.reserve(vertexCount);
    for (size_t v = 0; v < vertexCount; ++v)
        canon[v] = welded.emplace(weldKey(mesh.positions[v], mesh.normals[v], uvs[v]), uint32_t(welded.size())).first->second;
    const size_t canonCount = welded.size();
    std::vector<Vec3f> unitNormal(canonCount, Vec3f(0.f));
    for (size_t v = 0; v < vertexCount; ++v) unitNormal[canon[v]] = normalizedOrZero(mesh.normals[v]);

    // 2. Per-face tangent directions. MikkTSpace groups the faces around a vertex by whether their
    //    uv mapping preserves orientation: the two sides of a mirror seam get separate tangents.
    std::vector<FaceTangent> faces(mesh.triangles.size());
    for (size_t f = 0; f < mesh.triangles.size(); ++f) {
        const glm::uvec3& t = mesh.triangles[f];
        Vec3f p[3] = {mesh.positions[t.x], mesh.positions[t.y], mesh.positions[t.z]};
        Vec2f uv[3] = {uvs[t.x], uvs[t.y], uvs[t.z]};
        faces[f] = faceTangent(p, uv);
    }
    // Group g = 2·canonical vertex + (orientation preserving ? 0 : 1).
    std::vector<Vec3f> sum(2 * canonCount, Vec3f(0.f));
    std::vector<uint8_t> groupUsed(2 * canonCount, 0);
    for (size_t f = 0; f < faces.size(); ++f)
        if (faces[f].orientationKnown)
            for (int k = 0; k < 3; ++k) groupUsed[2 * canon[mesh.triangles[f][k]] + (faces[f].preservesOrientation ? 0 : 1)] = 1;
    // A uv-degenerate face has no orientation of its own: each corner joins the group already at its
    // vertex (the preserving one first), as MikkTSpace lets such faces join any group.
    auto cornerGroup = [&](size_t f, int k) {
        uint32_t c = canon[mesh.triangles[f][k]];
        if (faces[f].orientationKnown) return 2 * c + (faces[f].preservesOrientation ? 0u : 1u);
        return groupUsed[2 * c] || !groupUsed[2 * c + 1] ? 2 * c : 2 * c + 1;
    };

    // 3. Accumulate: each corner adds its face's tangent projected into the tangent plane of the
    //    vertex normal, weighted by the corner's angle measured in that plane (Mikkelsen 2008,
    //    section 4.2: angle weights make the result independent of how a surface is triangulated).
    for (size_t f = 0; f < faces.size(); ++f) {
        if (faces[f].dir == Vec3f(0.f)) continue;
        const glm::uvec3& t = mesh.triangles[f];
        for (int k = 0; k < 3; ++k) {
            uint32_t g = cornerGroup(f, k);
            const Vec3f& n = unitNormal[g / 2];
            const Vec3f& p = mesh.positions[t[k]];
            Vec3f toNext = normalizedOrZero(projectOntoPlane(mesh.positions[t[(k + 1) % 3]] - p, n));
            Vec3f toPrev = normalizedOrZero(projectOntoPlane(mesh.positions[t[(k + 2) % 3]] - p, n));
            float angle = std::acos(std::clamp(glm::dot(toNext, toPrev), -1.f, 1.f));
            sum[g] += angle * normalizedOrZero(projectOntoPlane(faces[f].dir, n));
        }
    }

    // 4. One tangent per group; a vertex whose corners fall into both of its groups is split.
    std::vector<Vec4f> tangents(vertexCount, Vec4f(0.f));
    std::vector<uint32_t> groupOfVertex(vertexCount, kInvalidId), splitOf(vertexCount, kInvalidId);
    auto tangentOf = [&](uint32_t g) {
        const Vec3f& n = unitNormal[g / 2];
        Vec3f t = normalizedOrZero(sum[g]);
        if (t == Vec3f(0.f) && n != Vec3f(0.f)) {
            // No usable face (all uv-degenerate): any tangent orthogonal to the normal.
            Vec3f b;
            coordinateSystem(n, t, b);
        }
        return Vec4f(t, g % 2 == 0 ? 1.f : -1.f);
    };
    size_t added = 0;
    for (size_t f = 0; f < mesh.triangles.size(); ++f) {
        for (int k = 0; k < 3; ++k) {
            uint32_t v = mesh.triangles[f][k];
            uint32_t g = cornerGroup(f, k);
            if (groupOfVertex[v] == kInvalidId) {
                groupOfVertex[v] = g;
                tangents[v] = tangentOf(g);
            } else if (groupOfVertex[v] != g) {
                if (splitOf[v] == kInvalidId) {
                    splitOf[v] = uint32_t(mesh.positions.size());
                    mesh.positions.push_back(mesh.positions[v]);
                    mesh.normals.push_back(mesh.normals[v]);
                    for (auto& set : mesh.texcoords)
                        if (!set.empty()) set.push_back(set[v]);
                    tangents.push_back(tangentOf(g));
                    ++added;
                }
                mesh.triangles[f][k] = splitOf[v];
            }
        }
    }
    mesh.tangents = std::move(tangents);
    return added;
}

void unweldWithFlatNormals(TriangleMesh& mesh) {
    TriangleMesh flat;
    flat.positions.reserve(3 * mesh.triangles.size());
    flat.normals.reserve(3 * mesh.triangles.size());
    for (int s = 0; s < 2; ++s)
        if (!mesh.texcoords[s].empty()) flat.texcoords[s].reserve(3 * mesh.triangles.size());
    bool hasTangents = !mesh.tangents.empty();
    for (const glm::uvec3& t : mesh.triangles) {
        Vec3f n = normalizedOrZero(glm::cross(mesh.positions[t.y] - mesh.positions[t.x], mesh.positions[t.z] - mesh.positions[t.x]));
        uint32_t base = uint32_t(flat.positions.size());
        for (int k = 0; k < 3; ++k) {
            flat.positions.push_back(mesh.positions[t[k]]);
            flat.normals.push_back(n);
            for (int s = 0; s < 2; ++s)
                if (!mesh.texcoords[s].empty()) flat.texcoords[s].push_back(mesh.texcoords[s][t[k]]);
            if (hasTangents) flat.tangents.push_back(mesh.tangents[t[k]]);
        }
        flat.triangles.emplace_back(base, base + 1, base + 2);
    }
    mesh.positions = std::move(flat.positions);
    mesh.normals = std::move(flat.normals);
    for (int s = 0; s < 2; ++s) mesh.texcoords[s] = std::move(flat.texcoords[s]);
    mesh.tangents = std::move(flat.tangents);
    mesh.triangles = std::move(flat.triangles);
}

}  // namespace tessera
