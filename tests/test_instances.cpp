// Mesh instances (issue 23 item 5): meshes named by several nodes are stored once and traced through
// a two-level structure in every backend. Our structures (bvh, sbvh, kdtree) and the brute-force
// backend share one top level and transform rays with one function, so their records on an
// instanced scene are bit-identical; every structure, Embree's instance API included, agrees with
// brute force over the scene's flattened copy (the validator's ties aside); the loader instances
// what is named twice and keeps emitters flat; an instanced scene with textures, normal maps and
// alpha cut-outs renders as its flattened copy does.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <array>
#include <cmath>
#include <filesystem>

#include "accel/accel.h"
#include "accel/brute_force_accel.h"
#include "core/rng.h"
#include "geometry/instances.h"
#include "integrators/integrator.h"
#include "render/renderer.h"
#include "materials/material.h"
#include "scene/camera.h"
#include "scene/gltf_loader.h"
#include "validation/instanced_scenes.h"
#include "validation/validate.h"
#include "gltf_test_files.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

/// A random triangle soup of `n` triangles in [−1, 1]³ (sizes 0.05–0.5).
TriangleMesh soupMesh(Pcg32& rng, int n, uint32_t material) {
    TriangleMesh m;
    m.name = "soup";
    m.materialId = material;
    for (int i = 0; i < n; ++i) {
        Vec3f c(2.f * rng.nextFloat() - 1.f, 2.f * rng.nextFloat() - 1.f, 2.f * rng.nextFloat() - 1.f);
        float size = 0.05f + 0.45f * rng.nextFloat();
        for (int k = 0; k < 3; ++k)
            m.positions.push_back(c + size * Vec3f(rng.nextFloat() - 0.5f, rng.nextFloat() - 0.5f, rng.nextFloat() - 0.5f));
        m.triangles.emplace_back(3 * i, 3 * i + 1, 3 * i + 2);
    }
    return m;
}

/// Two prototypes (a UV sphere mesh; a triangle soup plus a second mesh) placed by 100 instances
/// with random rotations, non-uniform scales (every fifth mirrored) and translations over a
/// 10 × 10 grid; a flat ground mesh and an analytic sphere beside them.
SceneGeometry randomInstancedScene(uint64_t seed) {
    Pcg32 rng(seed, 0);
    SceneGeometry g;
    TriangleMesh ground;
    ground.name = "ground";
    ground.positions = {{-12.f, -1.5f, -12.f}, {12.f, -1.5f, -12.f}, {12.f, -1.5f, 12.f}, {-12.f, -1.5f, 12.f}};
    ground.triangles = {{0, 2, 1}, {0, 3, 2}};
    g.meshes.push_back(ground);
    g.spheres.push_back(Sphere{"ball", Vec3f(0.f, 3.f, 0.f), 1.5f, 0});
    SceneGeometry ball, soup;
    ball.meshes.push_back(test::makeUvSphereMesh(Vec3f(0.f), 1.f, 6, 12, 0));
    soup.meshes.push_back(soupMesh(rng, 60, 0));
    soup.meshes.push_back(soupMesh(rng, 20, 0));
    g.prototypes = {ball, soup};
    for (int i = 0; i < 100; ++i) {
        Mat4d m = glm::translate(Mat4d(1.0), Vec3d(2.2 * (i % 10) - 10.0, 0.0, 2.2 * (i / 10) - 10.0));
        m = glm::rotate(m, 6.283 * double(rng.nextFloat()), glm::normalize(Vec3d(rng.nextFloat(), rng.nextFloat() + 0.1, rng.nextFloat())));
        Vec3d scale(0.4 + 0.6 * rng.nextFloat(), 0.4 + 0.6 * rng.nextFloat(), 0.4 + 0.6 * rng.nextFloat());
        if (i % 5 == 0) scale.x = -scale.x;
        m = glm::scale(m, scale);
        MeshInstance inst;
        EXPECT_TRUE(makeMeshInstance(uint32_t(i % 2), m, inst));
        g.instances.push_back(inst);
    }
    return g;
}

bool sameRecord(const Hit& a, const Hit& b) {
    return a.t == b.t && a.u == b.u && a.v == b.v && a.geomId == b.geomId && a.primId == b.primId && a.instId == b.instId &&
           a.ng == b.ng;
}

}  // namespace

TEST(Instances, OurStructuresGiveTheBruteForceRecordBitForBit) {
    SceneGeometry g = randomInstancedScene(7);
    std::unique_ptr<Accel> brute = createAccel("brute", g);
    InstanceFlattening flattening(g);
    SceneGeometry flat = flattening.flatten();
    BruteForceAccel flatBrute(flat);
    std::vector<Ray> rays;
    for (RayKind kind : {RayKind::Primary, RayKind::Random, RayKind::Diffuse})
        for (const Ray& r : generateRays(flat, flatBrute, kind, 1000, 3)) rays.push_back(r);
    size_t instanceHits = 0;
    for (const char* name : {"bvh", "sbvh", "kdtree"}) {
        std::unique_ptr<Accel> accel = createAccel(name, g);
        size_t differ = 0, occludedDiffer = 0;
        for (const Ray& r : rays) {
            Hit a, b;
            bool ha = accel->intersect(r, a), hb = brute->intersect(r, b);
            Hit c;
            bool hc = accel->intersectCoherent(r, c);
            if (ha != hb || (ha && !sameRecord(a, b)) || hc != ha || (hc && !sameRecord(a, c))) ++differ;
            if (accel->occluded(r) != ha) ++occludedDiffer;
            instanceHits += ha && a.instId != kInvalidId;
        }
        EXPECT_GT(instanceHits, rays.size() / 10) << name;  // many rays end on an instance: the test sees them
        instanceHits = 0;
        EXPECT_EQ(differ, 0u) << name << " of " << rays.size() << " rays";
        EXPECT_EQ(occludedDiffer, 0u) << name;
        EXPECT_EQ(accel->stats().primitives, g.primitiveCount() + g.instancedPrimitiveCount()) << name;
    }
}

TEST(Instances, EveryStructureAgreesWithTheFlattenedCopy) {
    SceneGeometry g = randomInstancedScene(11);
    InstanceFlattening flattening(g);
    SceneGeometry flat = flattening.flatten();
    BruteForceAccel flatBrute(flat);
    std::unique_ptr<Accel> embree = createAccel("embree", g);
    FlattenedIds embreeIds(*embree, flattening);
    for (const std::string& name : accelNames()) {
        std::unique_ptr<Accel> accel = createAccel(name, g);
        FlattenedIds ids(*accel, flattening);
        for (RayKind kind : kValidationRayKinds) {
            std::vector<Ray> rays = generateRays(flat, flatBrute, kind, 400, 5);
            ValidationResult vsFlat = compareAccels(ids, flatBrute, flat, rays, kind);
            EXPECT_EQ(vsFlat.errors, 0u) << name << " vs flattened brute force, " << toString(kind) << ": "
                                         << (vsFlat.examples.empty() ? "" : vsFlat.examples[0].reason);
            ValidationResult vsEmbree = compareAccels(ids, embreeIds, flat, rays, kind);
            EXPECT_EQ(vsEmbree.errors, 0u) << name << " vs Embree's instanced scene, " << toString(kind);
            // Grazing rays are aimed at edges: a tenth of them are ties there, none elsewhere.
            size_t minimum = kind == RayKind::Grazing ? rays.size() * 3 / 4 : rays.size() * 9 / 10;
            EXPECT_GT(vsFlat.agreements, minimum) << name << ", " << toString(kind);
        }
    }
}

TEST(Instances, AMissingInstanceIsAnError) {
    // The comparison must see instances: without the last one, rays ending on it disagree.
    SceneGeometry g = randomInstancedScene(13);
    InstanceFlattening flattening(g);
    SceneGeometry flat = flattening.flatten();
    BruteForceAccel flatBrute(flat);
    SceneGeometry fewer = g;
    fewer.instances.pop_back();
    std::unique_ptr<Accel> accel = createAccel("bvh", fewer);
    InstanceFlattening fewerFlattening(fewer);  // same numbering for every instance that is left
    FlattenedIds ids(*accel, fewerFlattening);
    std::vector<Ray> rays = generateRays(flat, flatBrute, RayKind::Primary, 1500, 5);
    EXPECT_GT(compareAccels(ids, flatBrute, flat, rays, RayKind::Primary).errors, 0u);
}

namespace {

/// A glTF scene: a floor (one node), an emissive quad named by two nodes, and a textured,
/// normal-mapped, alpha-masked quad mesh named by five nodes (rotated, scaled, one mirrored), a
/// camera. `path` gets the file.
void writeInstancedGltf(const std::string& path) {
    test::GltfBuilder b;
    auto quad = [&](std::vector<float> pos, std::vector<float> nrm) {
        int p = b.positions(pos), n = b.floats(nrm, 3, "VEC3");
        int uv = b.floats({0, 0, 1, 0, 1, 1, 0, 1}, 2, "VEC2");
        int ix = b.indices({0, 1, 2, 0, 2, 3});
        return std::array<int, 4>{p, n, uv, ix};
    };
    auto floor = quad({-4, 0, 4, 4, 0, 4, 4, 0, -4, -4, 0, -4}, {0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0});
    auto card = quad({-0.5f, 0, 0, 0.5f, 0, 0, 0.5f, 1, 0, -0.5f, 1, 0}, {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1});
    auto light = quad({-0.5f, 0, -0.5f, 0.5f, 0, -0.5f, 0.5f, 0, 0.5f, -0.5f, 0, 0.5f}, {0, -1, 0, 0, -1, 0, 0, -1, 0, 0, -1, 0});
    // 8×8 texels: a colour checker with holes (alpha 0) in one corner square; a bumpy normal map.
    std::vector<uint8_t> rgba, normal;
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            bool odd = (x / 2 + y / 2) % 2;
            rgba.insert(rgba.end(), {uint8_t(odd ? 220 : 40), uint8_t(odd ? 60 : 200), 90, uint8_t(x < 3 && y < 3 ? 0 : 255)});
            normal.insert(normal.end(), {uint8_t(128 + 60 * ((x % 2) ? 1 : -1)), uint8_t(128 + 40 * ((y % 2) ? 1 : -1)), 230});
        }
    int colorTex = b.texture(b.image(test::pngBytes(8, 8, 4, rgba), true));
    int normalTex = b.texture(b.image(test::pngBytes(8, 8, 3, normal), true));
    b.doc["materials"] = nlohmann::json::array(
        {{{"pbrMetallicRoughness", {{"baseColorFactor", {0.8, 0.8, 0.8, 1}}, {"metallicFactor", 0.0}, {"roughnessFactor", 1.0}}}},
         {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", colorTex}}}, {"metallicFactor", 0.0}, {"roughnessFactor", 0.6}}},
          {"normalTexture", {{"index", normalTex}}},
          {"alphaMode", "MASK"},
          {"doubleSided", true}},
         {{"emissiveFactor", {1, 1, 1}}, {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 8.0}}}}}}});
    auto prim = [](std::array<int, 4> q, int material) {
        return nlohmann::json{{"attributes", {{"POSITION", q[0]}, {"NORMAL", q[1]}, {"TEXCOORD_0", q[2]}}}, {"indices", q[3]}, {"material", material}};
    };
    b.doc["meshes"] = nlohmann::json::array({{{"primitives", {prim(floor, 0)}}}, {{"primitives", {prim(card, 1)}}}, {{"primitives", {prim(light, 2)}}}});
    b.doc["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 0.9}, {"znear", 0.01}}}}};
    nlohmann::json nodes = nlohmann::json::array();
    nodes.push_back({{"camera", 0}, {"translation", {0, 1.2, 4.5}}});
    nodes.push_back({{"mesh", 0}});
    nodes.push_back({{"mesh", 2}, {"translation", {-0.8, 2.6, 0}}});
    nodes.push_back({{"mesh", 2}, {"translation", {0.9, 2.4, -0.5}}});
    nodes.push_back({{"mesh", 1}, {"translation", {-1.6, 0, 0}}});
    nodes.push_back({{"mesh", 1}, {"translation", {0, 0, -0.5}}, {"rotation", {0, 0.2588, 0, 0.9659}}, {"scale", {1.5, 1.2, 1}}});
    nodes.push_back({{"mesh", 1}, {"translation", {1.5, 0, 0.3}}, {"scale", {-1, 1, 1}}});
    nodes.push_back({{"mesh", 1}, {"translation", {0.6, 0.2, 1.2}}, {"rotation", {0.2, 0.3, 0, 0.93}}, {"scale", {0.7, 0.7, 0.7}}});
    nodes.push_back({{"mesh", 1}, {"translation", {-0.7, 0.1, 1.5}}, {"rotation", {0, 0.7071, 0, 0.7071}}});
    b.doc["nodes"] = nodes;
    nlohmann::json roots = nlohmann::json::array();
    for (size_t i = 0; i < nodes.size(); ++i) roots.push_back(i);
    b.doc["scenes"] = {{{"nodes", roots}}};
    b.doc["scene"] = 0;
    b.write(path);
}

double rmse(const std::vector<float>& a, const std::vector<float>& b, double& mean, size_t& differing) {
    double sumSq = 0, sum = 0;
    differing = 0;
    for (size_t i = 0; i < a.size(); i += 4) {
        bool d = false;
        for (int c = 0; c < 3; ++c) {
            double e = double(a[i + c]) - double(b[i + c]);
            sumSq += e * e, sum += b[i + c], d |= a[i + c] != b[i + c];
        }
        differing += d;
    }
    mean = sum / double(3 * a.size() / 4);
    return std::sqrt(sumSq / double(3 * a.size() / 4));
}

}  // namespace

TEST(Instances, TheLoaderInstancesMeshesNamedTwiceAndKeepsEmittersFlat) {
    std::string path = (test::tempDir("instances-loader") / "scene.gltf").string();
    writeInstancedGltf(path);
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(path, warnings);
    // The card (5 nodes) is one prototype; the floor (1 node) and the emitter's two copies are flat.
    ASSERT_EQ(scene.geometry.prototypes.size(), 1u);
    EXPECT_EQ(scene.geometry.instances.size(), 5u);
    EXPECT_EQ(scene.geometry.meshes.size(), 3u);
    EXPECT_EQ(scene.lights().size(), 4u);  // 2 emissive quads × 2 triangles: lights stay world triangles
    EXPECT_TRUE(instanceMirrors(scene.geometry.instances[2]));
    SceneLoadOptions flatOptions;
    flatOptions.instanceMeshes = false;
    Scene flat = loadGltfScene(path, warnings, flatOptions);
    EXPECT_TRUE(flat.geometry.prototypes.empty());
    EXPECT_EQ(flat.geometry.meshes.size(), 8u);
    // Instance boxes are the prototype's box transformed and padded by 1e-5 of their magnitude.
    Bounds3f a = flat.geometry.bounds(), b = scene.geometry.bounds();
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(a.lower[k], b.lower[k], 1e-4f);
        EXPECT_NEAR(a.upper[k], b.upper[k], 1e-4f);
    }
}

TEST(Instances, AnInstancedSceneWithTexturesAndCutOutsRendersAsItsFlattenedCopy) {
    std::string path = (test::tempDir("instances-render") / "scene.gltf").string();
    writeInstancedGltf(path);
    std::vector<std::string> warnings;
    Scene instanced = loadGltfScene(path, warnings);
    SceneLoadOptions flatOptions;
    flatOptions.instanceMeshes = false;
    Scene flat = loadGltfScene(path, warnings, flatOptions);
    RenderOptions options{.spp = 4, .threads = 2, .seed = 5};
    auto render = [&](const Scene& s, const std::string& accel) {
        return test::renderScene(s, "ptnee", 48, 36, options, accel).film.rgba();
    };
    std::vector<float> reference = render(flat, "embree");
    std::vector<float> brute = render(instanced, "brute");
    for (const std::string& accel : accelNames()) {
        std::vector<float> image = render(instanced, accel);
        double mean = 0;
        size_t differing = 0;
        // Instanced hits are computed in object space: t, the hit point and the shading frame
        // differ from the flattened copy's by float rounding, which moves pixels by ulps (measured:
        // RMSE 3e-6 of the mean, Embree's 1.7e-6) and a path elsewhere only where it grazes an edge.
        double e = rmse(image, reference, mean, differing);
        EXPECT_GT(mean, 0.02) << accel;
        EXPECT_LT(e, 3e-5 * mean) << accel << ": " << differing << " pixels differ from the flattened render";
        std::cout << accel << ": rmse " << e / mean << " of the mean against the flattened render, " << differing << " of 1728 pixels differ\n";
        if (accel != "embree") {
            rmse(image, brute, mean, differing);
            EXPECT_EQ(differing, 0u) << accel << " differs from brute force on the instanced scene";
        }
    }
}

TEST(Instances, SurfaceInteractionsMatchTheFlattenedCopy) {
    // What shading reads at a camera ray's hit — point, normals (normal-mapped), material, texture
    // values — is the same on an instance as on its flattened copy, up to float rounding.
    std::string path = (test::tempDir("instances-si") / "scene.gltf").string();
    writeInstancedGltf(path);
    std::vector<std::string> warnings;
    Scene instanced = loadGltfScene(path, warnings);
    SceneLoadOptions flatOptions;
    flatOptions.instanceMeshes = false;
    Scene flat = loadGltfScene(path, warnings, flatOptions);
    std::unique_ptr<Accel> a = createAccel("bvh", instanced.geometry), b = createAccel("bvh", flat.geometry);
    Camera camera(*instanced.camera, 96, 72);
    float maxDp = 0.f, maxDns = 0.f, maxDcolor = 0.f;
    size_t onInstances = 0, differentHits = 0;
    for (int y = 0; y < 72; ++y)
        for (int x = 0; x < 96; ++x) {
            Ray r = camera.generateRay(Vec2f(float(x) + 0.5f, float(y) + 0.5f), Vec2f(0.5f));
            Hit ha, hb;
            bool fa = a->intersect(r, ha), fb = b->intersect(r, hb);
            if (fa != fb || std::abs(ha.t - hb.t) > 1e-4f * hb.t) {
                ++differentHits;
                continue;
            }
            if (!fa || ha.instId == kInvalidId) continue;
            ++onInstances;
            SurfaceInteraction sa = instanced.interaction(r, ha), sb = flat.interaction(r, hb);
            maxDp = std::max(maxDp, glm::length(sa.p - sb.p));
            maxDns = std::max(maxDns, glm::length(sa.ns - sb.ns));
            EXPECT_EQ(sa.materialId, sb.materialId);
            BsdfParams pa = instanced.bsdfParams(sa, 0.01f), pb = flat.bsdfParams(sb, 0.01f);
            maxDcolor = std::max(maxDcolor, maxComponent(glm::abs(pa.baseColor - pb.baseColor)));
        }
    EXPECT_GT(onInstances, 500u);
    EXPECT_LT(differentHits, 10u);  // rays through a cut-out's contour or an edge, within rounding
    EXPECT_LT(maxDp, 1e-5f);
    EXPECT_LT(maxDns, 1e-4f);
    EXPECT_LT(maxDcolor, 1e-3f);
    std::cout << "instances " << onInstances << ", different hits " << differentHits << ", max |dp| " << maxDp << ", |dns| " << maxDns
              << ", |dbaseColor| " << maxDcolor << "\n";
}

TEST(Instances, RaySetsOfAnInstancedSceneStartOnItsSurfaces) {
    // bench-accel and validate-accel generate diffuse and shadow rays from the hits of their
    // oracle: on an instanced scene those hits lie on instances, whose points are in world space.
    SceneGeometry g = randomInstancedScene(17);
    SceneGeometry flat = InstanceFlattening(g).flatten();
    std::unique_ptr<Accel> oracle = createAccel("bvh", g);
    BruteForceAccel flatOracle(flat);
    for (RayKind kind : {RayKind::Diffuse, RayKind::Shadow}) {
        // A ray that leaves a surface at its origin, traced back from 0.01 along it, meets that
        // surface (in the flattened copy) within 0.011; the rays that top up a set when the camera
        // sees too little start anywhere. As many start on a surface as on the flattened copy.
        auto onSurface = [&](const std::vector<Ray>& rays) {
            size_t n = 0;
            for (const Ray& r : rays) {
                Vec3f d = glm::normalize(r.d);
                n += flatOracle.occluded(Ray{r.o + 0.01f * d, -d, 0.f, 0.011f});
            }
            return n;
        };
        size_t instancedCount = onSurface(generateRays(g, *oracle, kind, 400, 9));
        size_t flatCount = onSurface(generateRays(flat, flatOracle, kind, 400, 9));
        EXPECT_GT(flatCount, 100u) << toString(kind);
        EXPECT_GE(instancedCount + 8, flatCount) << toString(kind);
    }
}
