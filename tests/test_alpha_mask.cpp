// Cut-out geometry (glTF alphaMode MASK, issue 16 item 3): every backend drops the hits an alpha
// mask drops, for every ray kind, so their hit records stay identical. A ray through a hole passes,
// one on an opaque texel hits, the nearest *kept* triangle is returned when a masked one lies in
// front (also inside one SIMD leaf block), occluded() agrees, validate-accel finds no error against
// Embree's filter functions, and a fence casts the same shadow with every --accel.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>

#include "accel/bvh_accel.h"
#include "accel/kdtree_accel.h"
#include "core/rng.h"
#include "geometry/alpha_mask.h"
#include "scene/scene_loader.h"
#include "validation/validate.h"
#include "gltf_test_files.h"
#include "test_helpers.h"

using namespace tessera;
using namespace tessera::test;

namespace {

/// One-level RGBA image whose alpha is alpha(x, y); colour white.
template <class F>
std::unique_ptr<Image> makeAlphaImage(int w, int h, F alpha) {
    auto img = std::make_unique<Image>();
    img->name = "alpha test image";
    ImageLevel level;
    level.width = w, level.height = h;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) level.texels.push_back(Vec4f(1.f, 1.f, 1.f, alpha(x, y)));
    img->levels.push_back(std::move(level));
    return img;
}

/// The fence texture: 4×4-texel checkerboard squares of holes (alpha 0) and opaque texels
/// (alpha 1), and, in the top four rows, a ramp from 0 to 1 across, so that bilinear filtering puts
/// the 0.5 cutoff contour inside texels too.
std::unique_ptr<Image> fenceImage() {
    return makeAlphaImage(16, 16, [](int x, int y) {
        if (y < 4) return float(x) / 15.f;
        return ((x / 4 + y / 4) % 2) ? 0.f : 1.f;
    });
}

/// A planar grid of n × n cells (2 triangles each) spanning origin + [0, 1]·eu + [0, 1]·ev, with
/// texture coordinates uvScale·(s, t) in set `texCoord` (the other set left empty).
TriangleMesh gridMesh(const std::string& name, Vec3f origin, Vec3f eu, Vec3f ev, int n, float uvScale, int texCoord) {
    TriangleMesh m;
    m.name = name;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            float s = float(i) / float(n), t = float(j) / float(n);
            m.positions.push_back(origin + s * eu + t * ev);
            m.texcoords[texCoord].push_back(uvScale * Vec2f(s, t));
        }
    auto id = [&](int i, int j) { return uint32_t(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            m.triangles.emplace_back(id(i, j), id(i + 1, j), id(i + 1, j + 1));
            m.triangles.emplace_back(id(i, j), id(i + 1, j + 1), id(i, j + 1));
        }
    return m;
}

std::shared_ptr<const AlphaMask> makeMask(const Image* image, int texCoord, FilterMode filter, WrapMode wrap, float factor,
                                          float cutoff) {
    auto mask = std::make_shared<AlphaMask>();
    mask->texture.image = image;
    mask->texture.texCoord = uint8_t(texCoord);
    mask->texture.filter = filter;
    mask->texture.wrapS = mask->texture.wrapT = wrap;
    mask->factor = factor;
    mask->cutoff = cutoff;
    return mask;
}

/// Geometry plus the images its masks point into.
struct MaskedScene {
    std::vector<std::unique_ptr<Image>> images;
    SceneGeometry g;
};

/// The validation scene: three fences (two stacked parallel ones and an oblique one crossing them,
/// with different filters, wraps, texture-coordinate sets, factors and cutoffs), an opaque
/// triangle-mesh sphere behind them and an analytic sphere among them (leaves mixing spheres and
/// cut-out triangles).
MaskedScene fenceValidationScene() {
    MaskedScene s;
    s.images.push_back(fenceImage());
    const Image* img = s.images.back().get();
    TriangleMesh a = gridMesh("fence A", Vec3f(-1, -1, 0), Vec3f(2, 0, 0), Vec3f(0, 2, 0), 8, 1.f, 0);
    a.alphaMask = makeMask(img, 0, FilterMode::Linear, WrapMode::Repeat, 1.f, 0.5f);
    TriangleMesh b = gridMesh("fence B", Vec3f(-1, -1, -0.4f), Vec3f(2, 0, 0), Vec3f(0, 2, 0), 6, 2.5f, 1);
    b.alphaMask = makeMask(img, 1, FilterMode::Nearest, WrapMode::MirroredRepeat, 0.8f, 0.3f);
    TriangleMesh c = gridMesh("fence C", Vec3f(-1.2f, -1, -1), Vec3f(2.4f, 0, 1.f), Vec3f(0, 2, 0), 8, 1.5f, 0);
    c.alphaMask = makeMask(img, 0, FilterMode::Linear, WrapMode::ClampToEdge, 1.f, 0.5f);
    s.g.meshes.push_back(std::move(a));
    s.g.meshes.push_back(std::move(b));
    s.g.meshes.push_back(std::move(c));
    s.g.meshes.push_back(makeUvSphereMesh(Vec3f(0.f, 0.f, -1.3f), 0.6f, 12, 24, 0));
    s.g.spheres.push_back(Sphere{"ball", Vec3f(0.4f, 0.3f, -0.2f), 0.15f, 0});
    return s;
}

/// Every backend, plus our structures' portable (SSE2) kernels: on an AVX2 machine nothing else
/// would run them.
std::vector<std::pair<std::string, std::unique_ptr<Accel>>> allBackends(const SceneGeometry& g) {
    std::vector<std::pair<std::string, std::unique_ptr<Accel>>> all;
    for (const std::string& name : accelNames()) all.emplace_back(name, createAccel(name, g));
    auto bvh = std::make_unique<BvhAccel>(g, AccelOptions{});
    bvh->forcePortableKernels();
    all.emplace_back("bvh (portable)", std::move(bvh));
    BvhConfig sbvhConfig;
    sbvhConfig.spatialSplits = true;
    auto sbvh = std::make_unique<BvhAccel>(g, AccelOptions{}, sbvhConfig);
    sbvh->forcePortableKernels();
    all.emplace_back("sbvh (portable)", std::move(sbvh));
    auto kd = std::make_unique<KdTreeAccel>(g, AccelOptions{});
    kd->forcePortableKernels();
    all.emplace_back("kdtree (portable)", std::move(kd));
    return all;
}

/// The record of `accel` for `ray` through all three queries, which must agree.
bool traceAll(const Accel& accel, const Ray& ray, Hit& hit, const std::string& what) {
    bool found = accel.intersect(ray, hit);
    Hit coherent;
    EXPECT_EQ(accel.intersectCoherent(ray, coherent), found) << what;
    if (found) {
        EXPECT_EQ(coherent.geomId, hit.geomId) << what;
        EXPECT_EQ(coherent.primId, hit.primId) << what;
        EXPECT_EQ(coherent.t, hit.t) << what;
    }
    EXPECT_EQ(accel.occluded(ray), found) << what;
    return found;
}

}  // namespace

TEST(AlphaMask, KeepsWhereFactorTimesTextureAlphaReachesTheCutoff) {
    // 2 × 1 texels: alpha 0.25 (left) and 0.75 (right); nearest lookups at the texel centres.
    auto img = makeAlphaImage(2, 1, [](int x, int) { return x == 0 ? 0.25f : 0.75f; });
    TriangleMesh m = gridMesh("quad", Vec3f(0), Vec3f(1, 0, 0), Vec3f(0, 1, 0), 1, 1.f, 0);
    // Triangle 0 is (v00, v10, v11): barycentrics (u, v) weigh v10 = (1, 0) and v11 = (1, 1), so the
    // point (s, t) has u = s − t, v = t.
    auto keeps = [&](float s, float t) { return alphaMaskKeeps(m, 0, s - t, t); };
    EXPECT_TRUE(keeps(0.25f, 0.1f)) << "no mask: opaque";
    m.alphaMask = makeMask(img.get(), 0, FilterMode::Nearest, WrapMode::Repeat, 1.f, 0.5f);
    EXPECT_FALSE(keeps(0.25f, 0.1f));
    EXPECT_TRUE(keeps(0.75f, 0.1f));
    // The factor multiplies the texture: 0.75 × 0.6 = 0.45 < 0.5.
    m.alphaMask = makeMask(img.get(), 0, FilterMode::Nearest, WrapMode::Repeat, 0.6f, 0.5f);
    EXPECT_FALSE(keeps(0.75f, 0.1f));
    // Equal to the cutoff is kept (glTF: alpha ≥ alphaCutoff); 0.25 × 2 = 0.5 exactly.
    m.alphaMask = makeMask(img.get(), 0, FilterMode::Nearest, WrapMode::Repeat, 2.f, 0.5f);
    EXPECT_TRUE(keeps(0.25f, 0.1f));
    m.alphaMask = makeMask(img.get(), 0, FilterMode::Nearest, WrapMode::Repeat, 1.f, 0.2f);
    EXPECT_TRUE(keeps(0.25f, 0.1f));
    // No texture: the factor alone.
    auto untextured = std::make_shared<AlphaMask>();
    untextured->factor = 0.4f;
    untextured->cutoff = 0.5f;
    m.alphaMask = untextured;
    EXPECT_FALSE(keeps(0.75f, 0.1f));
    // The texture's own coordinate set: TEXCOORD_1 holding (1 − s, t) reads the other texel.
    TriangleMesh m1 = m;
    m1.texcoords[1] = m.texcoords[0];
    for (Vec2f& uv : m1.texcoords[1]) uv.x = 1.f - uv.x;
    m1.alphaMask = makeMask(img.get(), 1, FilterMode::Nearest, WrapMode::Repeat, 1.f, 0.5f);
    EXPECT_TRUE(alphaMaskKeeps(m1, 0, 0.25f - 0.1f, 0.1f));
    EXPECT_FALSE(alphaMaskKeeps(m1, 0, 0.75f - 0.1f, 0.1f));
    // A NaN alpha (NaN texture coordinates) drops the hit rather than keeping it at random.
    m1.texcoords[1][0] = Vec2f(std::nanf(""));
    EXPECT_FALSE(alphaMaskKeeps(m1, 0, 0.2f, 0.1f));
}

TEST(AlphaMask, HolesPassOpaqueTexelsHitAndTheNearestKeptTriangleWinsInEveryBackend) {
    // Two stacked quads, both cut-outs (z = 0 in front, z = −1 behind, rays travel down −z), and an
    // opaque quad at z = −2. Texture 2 × 2 texels: holes at texels (1, 0) and (0, 1) in front,
    // (0, 0) and (0, 1) behind. The triangles share a leaf (the fences alone: one four-lane BVH
    // block; the k-d tree's blocks hold eight), so a rejected lane of the nearest-lane search must
    // give way to the next-nearest lane of the same SIMD block.
    auto front = makeAlphaImage(2, 2, [](int x, int y) { return (x + y) % 2 ? 0.f : 1.f; });
    auto back = makeAlphaImage(2, 2, [](int x, int) { return x == 0 ? 0.f : 1.f; });
    // Variants: the two fences alone (four triangles: one BVH block of four lanes), with the
    // floor, and with the floor and a sphere.
    for (int variant : {0, 1, 2}) {
        const bool withFloor = variant >= 1, withSphere = variant == 2;
        SceneGeometry g;
        g.meshes.push_back(gridMesh("front", Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0), 1, 1.f, 0));
        g.meshes.back().alphaMask = makeMask(front.get(), 0, FilterMode::Nearest, WrapMode::Repeat, 1.f, 0.5f);
        g.meshes.push_back(gridMesh("back", Vec3f(0, 0, -1), Vec3f(1, 0, 0), Vec3f(0, 1, 0), 1, 1.f, 0));
        g.meshes.back().alphaMask = makeMask(back.get(), 0, FilterMode::Nearest, WrapMode::Repeat, 1.f, 0.5f);
        if (withFloor) g.meshes.push_back(gridMesh("floor", Vec3f(0, 0, -2), Vec3f(1, 0, 0), Vec3f(0, 1, 0), 1, 1.f, 0));
        // A sphere far to the side makes the one leaf a mixed (scalar) leaf.
        if (withSphere) g.spheres.push_back(Sphere{"aside", Vec3f(5, 5, -1), 0.1f, 0});
        struct Case {
            float s, t;         // point on the quads (texel (⌊2s⌋, ⌊2t⌋))
            uint32_t geomId;    // expected hit, kInvalidId: none
        };
        const Case cases[] = {
            {0.25f, 0.25f, 0},  // opaque front texel (0, 0)
            {0.75f, 0.75f, 0},  // opaque front texel (1, 1)
            {0.75f, 0.25f, 1},  // front hole (1, 0), back texel (1, 0) opaque
            {0.25f, 0.75f, 2},  // front hole (0, 1), back hole (0, 1): the opaque floor
        };
        for (auto& [name, accel] : allBackends(g)) {
            for (const Case& c : cases) {
                const char* setup = withSphere ? " (mixed leaf)" : withFloor ? " (with floor)" : " (fences only)";
                std::string what = name + setup + " at (" + std::to_string(c.s) + ", " + std::to_string(c.t) + ")";
                Ray ray;
                ray.d = Vec3f(0.01f, -0.02f, -1.f);  // slightly oblique: no axis-aligned special case
                ray.o = Vec3f(c.s, c.t, 0.f) - ray.d;  // meets z = 0 at (s, t), t = 1, 2, 3 at the quads
                Hit hit;
                bool found = traceAll(*accel, ray, hit, what);
                const uint32_t expected = c.geomId == 2 && !withFloor ? kInvalidId : c.geomId;
                ASSERT_EQ(found, expected != kInvalidId) << what;
                if (found) {
                    EXPECT_EQ(hit.geomId, expected) << what;
                }
                // The same ray stopped before the floor: occluded exactly when a fence keeps it.
                Ray shortRay = ray;
                shortRay.tMax = 2.5f;  // the floor lies at t ≈ 3
                Hit h2;
                EXPECT_EQ(traceAll(*accel, shortRay, h2, what + ", short"), c.geomId != 2) << what;
                // Upwards (+z) from between the back fence and the floor: the back fence, then the
                // front one.
                Ray up{Vec3f(c.s, c.t, -1.5f), Vec3f(0.f, 0.f, 1.f)};
                up.tMax = 2.f;
                Hit h3;
                bool fromBelow = traceAll(*accel, up, h3, what + ", upwards");
                bool backOpaque = c.s > 0.5f, frontOpaque = (c.s < 0.5f) == (c.t < 0.5f);
                uint32_t expectUp = backOpaque ? 1u : frontOpaque ? 0u : kInvalidId;
                EXPECT_EQ(fromBelow, expectUp != kInvalidId) << what << ", upwards";
                if (fromBelow) {
                    EXPECT_EQ(h3.geomId, expectUp) << what << ", upwards";
                }
            }
        }
    }
}

namespace {

/// validate-accel on the fence scene: `accel` against Embree, 1e5 rays over the four kinds.
void expectFenceValidates(const std::string& accelName, size_t raysPerKind) {
    MaskedScene s = fenceValidationScene();
    auto embree = createAccel("embree", s.g);
    std::vector<std::pair<std::string, std::unique_ptr<Accel>>> tested;
    tested.emplace_back(accelName, createAccel(accelName, s.g));
    if (accelName == "bvh" || accelName == "sbvh") {
        auto bvh = static_cast<BvhAccel*>(tested.back().second.get());
        EXPECT_EQ(bvh->checkInvariants(), "");
        BvhConfig config;
        config.spatialSplits = accelName == "sbvh";
        auto portable = std::make_unique<BvhAccel>(s.g, AccelOptions{}, config);
        portable->forcePortableKernels();
        tested.emplace_back(accelName + " (portable)", std::move(portable));
    } else if (accelName == "kdtree") {
        EXPECT_EQ(static_cast<KdTreeAccel*>(tested.back().second.get())->checkInvariants(), "");
        auto portable = std::make_unique<KdTreeAccel>(s.g, AccelOptions{});
        portable->forcePortableKernels();
        tested.emplace_back("kdtree (portable)", std::move(portable));
    }
    for (RayKind kind : kValidationRayKinds) {
        std::vector<Ray> rays = generateRays(s.g, *embree, kind, raysPerKind, /*seed=*/3);
        for (auto& [name, accel] : tested) {
            ValidationResult r = compareAccels(*accel, *embree, s.g, rays, kind);
            EXPECT_EQ(r.rays, rays.size());
            EXPECT_EQ(r.errors, 0u) << name << ", " << toString(kind) << " rays: " << toJson(r).dump();
            // Ties are rays through shared edges and vertices (and the mask's cutoff contour):
            // a small share, never a way to hide disagreement; grazing rays aim at edges and
            // vertices, so a good part of them are.
            size_t tieLimit = kind == RayKind::Grazing ? rays.size() / 4 : rays.size() / 50;
            EXPECT_LT(r.ties, tieLimit) << name << ", " << toString(kind);
        }
    }
}

}  // namespace

TEST(AlphaMask, ValidateAccelBvhOnFences) { expectFenceValidates("bvh", 25000); }
TEST(AlphaMask, ValidateAccelSbvhOnFences) { expectFenceValidates("sbvh", 25000); }
TEST(AlphaMask, ValidateAccelKdtreeOnFences) { expectFenceValidates("kdtree", 25000); }
// The validator's own reference (Embree with its filter functions) against brute force.
TEST(AlphaMask, ValidateAccelBruteOnFences) { expectFenceValidates("brute", 25000); }

TEST(AlphaMask, ValidatorSeesAStructureThatIgnoresTheMask) {
    // The same fences built without their masks, judged on the masked scene: rays through holes
    // now hit, and the validator must call them errors (so the tests above can fail).
    MaskedScene s = fenceValidationScene();
    SceneGeometry opaque = s.g;
    for (TriangleMesh& m : opaque.meshes) m.alphaMask.reset();
    auto embree = createAccel("embree", s.g);
    for (const char* name : {"bvh", "kdtree", "brute"}) {
        auto ignoring = createAccel(name, opaque);
        std::vector<Ray> rays = generateRays(s.g, *embree, RayKind::Primary, 4000, 3);
        ValidationResult r = compareAccels(*ignoring, *embree, s.g, rays, RayKind::Primary);
        EXPECT_GT(r.errors, rays.size() / 20) << name;
        // And Embree built without the masks is caught as a reference hitting holes.
        auto embreeOpaque = createAccel("embree", opaque);
        auto masked = createAccel(name, s.g);
        ValidationResult rr = compareAccels(*masked, *embreeOpaque, s.g, rays, RayKind::Primary);
        EXPECT_GT(rr.errors, rays.size() / 20) << name << " against an unmasked reference";
    }
}

TEST(AlphaMask, FenceCastsTheSameShadowWithEveryAccel) {
    // A cut-out fence (holes in a checkerboard, a ramp row) above an opaque floor, lit by a point
    // light above: the camera sees the floor through the holes and the fence's shadow on it.
    Scene scene;
    Material white;
    white.bsdf.baseColor = Rgb(0.8f);
    white.doubleSided = true;
    scene.materials.push_back(white);
    auto image = fenceImage();
    TriangleMesh fence = gridMesh("fence", Vec3f(-1, 1, 1), Vec3f(2, 0, 0), Vec3f(0, 0, -2), 8, 2.f, 0);
    fence.alphaMask = makeMask(image.get(), 0, FilterMode::Linear, WrapMode::Repeat, 1.f, 0.5f);
    scene.geometry.meshes.push_back(fence);
    scene.geometry.meshes.push_back(gridMesh("floor", Vec3f(-3, 0, 3), Vec3f(6, 0, 0), Vec3f(0, 0, -6), 4, 1.f, 0));
    scene.pointLights.push_back(PointLightDesc{Vec3f(0.2f, 3.f, 0.3f), Rgb(20.f)});
    scene.finalize();
    CameraDesc cam;
    cam.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.f, 3.5f, 3.f), glm::vec3(0.f, 0.3f, 0.f), glm::vec3(0, 1, 0)));
    cam.yfov = 0.9f;
    scene.camera = cam;

    RenderOptions options{.spp = 2, .threads = 2, .seed = 5};
    auto render = [&](const Scene& sc, const std::string& accel) {
        TestRender r = renderScene(sc, "ptnee", 48, 36, options, accel, /*maxDepth=*/2);
        EXPECT_EQ(r.stats.nonFiniteDropped, 0u) << accel;
        return r.film.rgba();
    };
    auto meanOf = [](const std::vector<float>& img) {
        double sum = 0;
        for (size_t i = 0; i < img.size(); i += 4) sum += img[i] + img[i + 1] + img[i + 2];
        return sum / double(img.size() / 4 * 3);
    };
    std::vector<float> brute = render(scene, "brute");
    std::vector<float> embree = render(scene, "embree");
    for (const char* accel : {"bvh", "sbvh", "kdtree"}) {
        std::vector<float> img = render(scene, accel);
        size_t differ = 0;
        double sumSq = 0;
        for (size_t i = 0; i < img.size(); ++i) {
            differ += img[i] != brute[i];
            double e = double(img[i]) - double(embree[i]);
            sumSq += e * e;
        }
        // Our structures decide every hit exactly as brute force does: the same bits.
        EXPECT_EQ(differ, 0u) << accel;
        // Embree's triangle test rounds t differently (ulps); its filter decides the mask alike.
        EXPECT_LT(std::sqrt(sumSq / double(img.size())), 1e-5 * meanOf(embree)) << accel;
    }
    // The mask matters: the same fence made opaque gives another image (the floor seen through
    // the holes and lit through them; the fence's top lit where it is opaque).
    Scene opaqueScene;
    opaqueScene.materials = scene.materials;
    opaqueScene.geometry = scene.geometry;
    opaqueScene.geometry.meshes[0].alphaMask.reset();
    opaqueScene.pointLights = scene.pointLights;
    opaqueScene.camera = scene.camera;
    opaqueScene.finalize();
    std::vector<float> opaque = render(opaqueScene, "bvh");
    double mean = meanOf(brute);
    size_t changed = 0;
    for (size_t i = 0; i < opaque.size(); i += 4) changed += std::abs(opaque[i] - brute[i]) > 0.2 * mean;
    EXPECT_GT(changed, opaque.size() / 4 / 10) << "holes let light and view through";
}

namespace {

/// A glTF a user could bring: a cut-out fence (8 × 8 grid over [−1, 1]² at z = 0, an RGBA PNG
/// base-colour texture whose alpha is fenceImage's pattern, alphaMode MASK) in front of an opaque
/// wall at z = −1; written as .gltf + .bin into `dir`.
std::string writeFenceGltf(const std::filesystem::path& dir) {
    GltfBuilder b;
    std::vector<uint8_t> rgba;
    std::unique_ptr<Image> pattern = fenceImage();
    for (const Vec4f& texel : pattern->levels[0].texels)
        for (float c : {texel.r, texel.g, texel.b, texel.a}) rgba.push_back(uint8_t(std::lround(255.f * c)));
    int texture = b.texture(b.image(pngBytes(16, 16, 4, rgba), /*inBufferView=*/true));
    auto grid = [&](float z, int n) {
        std::vector<float> xyz, uv;
        std::vector<uint32_t> ix;
        for (int j = 0; j <= n; ++j)
            for (int i = 0; i <= n; ++i) {
                float s = float(i) / float(n), t = float(j) / float(n);
                xyz.insert(xyz.end(), {-1.f + 2.f * s, 1.f - 2.f * t, z});
                uv.insert(uv.end(), {s, t});
            }
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                uint32_t a = uint32_t(j * (n + 1) + i), c = a + uint32_t(n + 1);
                ix.insert(ix.end(), {a, c, a + 1, a + 1, c, c + 1});
            }
        return nlohmann::json{{"attributes", {{"POSITION", b.positions(xyz)}, {"TEXCOORD_0", b.floats(uv, 2, "VEC2")}}},
                              {"indices", b.indices(ix)}};
    };
    nlohmann::json fence = grid(0.f, 8), wall = grid(-1.f, 2);
    fence["material"] = 0;
    wall["material"] = 1;
    b.doc["materials"] = {{{"name", "fence"}, {"alphaMode", "MASK"}, {"alphaCutoff", 0.5},
                           {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", texture}}}}}},
                          {{"name", "wall"}}};
    b.doc["meshes"] = {{{"primitives", {fence}}}, {{"primitives", {wall}}}};
    b.doc["nodes"] = {{{"mesh", 0}}, {{"mesh", 1}}};
    b.doc["scenes"] = {{{"nodes", {0, 1}}}};
    b.doc["scene"] = 0;
    std::string path = (dir / "fence.gltf").string();
    b.write(path);
    return path;
}

}  // namespace

TEST(AlphaMask, ValidateAccelOnACutOutGltf) {
    std::filesystem::path dir = tempDir("alpha-gltf");
    std::string path = writeFenceGltf(dir);
    // The geometry alone (validate-accel, bench-accel, the API): its masks' images must outlive the
    // Scene the loader built (SceneGeometry::maskImages).
    std::optional<CameraDesc> camera;
    std::vector<std::string> warnings;
    SceneGeometry g = loadGeometryFile(path, camera, warnings);
    ASSERT_EQ(g.meshes.size(), 2u);
    size_t masked = 0;
    for (const TriangleMesh& m : g.meshes) masked += m.alphaMask != nullptr;
    ASSERT_EQ(masked, 1u);
    // Texel (5, 9) is a hole, texel (4, 4) opaque: the fence's point (s, t) lies at (−1 + 2s, 1 − 2t).
    auto through = [](float s, float t) { return Ray{Vec3f(-1.f + 2.f * s, 1.f - 2.f * t, 1.f), Vec3f(0.f, 0.f, -1.f)}; };
    for (const std::string& name : accelNames()) {
        auto accel = createAccel(name, g);
        Hit hole, opaque;
        ASSERT_TRUE(accel->intersect(through(5.5f / 16.f, 9.5f / 16.f), hole)) << name;
        EXPECT_NEAR(hole.t, 2.f, 1e-5f) << name << ": through the hole to the wall";
        ASSERT_TRUE(accel->intersect(through(4.5f / 16.f, 4.5f / 16.f), opaque)) << name;
        EXPECT_NEAR(opaque.t, 1.f, 1e-5f) << name << ": the fence";
    }
    // The command itself, for every structure: no error against Embree.
    for (const char* accel : {"bvh", "sbvh", "kdtree", "brute"}) {
        std::filesystem::path out = dir / (std::string(accel) + ".json");
        std::string cmd = std::string(TESSERA_BINARY) + " validate-accel '" + path + "' --accel " + accel +
                          " --rays 20000 --json > '" + out.string() + "' 2> /dev/null";
        EXPECT_EQ(std::system(cmd.c_str()), 0) << accel;
        nlohmann::json j = nlohmann::json::parse(std::ifstream(out));
        EXPECT_EQ(j["errors"], 0) << accel << ": " << j.dump();
        EXPECT_EQ(j["alpha_masked_meshes"], 1) << accel;
        EXPECT_EQ(j["rays"], 20000) << accel;
    }
    std::filesystem::remove_all(dir);
}
