// The environment light in every integrator: furnaces with analytic answers (a convex Lambertian
// object under a constant environment), the orientation convention, importance sampling (χ²,
// relMSE with a small sun) and agreement of the integrators on environment-lit scenes.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>

#include "core/error.h"
#include "integrators/integrator.h"
#include "io/image_output.h"
#include "render/renderer.h"
#include "scene/gltf_loader.h"
#include "test_agreement.h"
#include "test_env_images.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

CameraDesc lookAtCamera(Vec3f eye, Vec3f target, float yfov, Vec3f up = Vec3f(0.f, 1.f, 0.f)) {
    CameraDesc d;
    d.cameraToWorld = glm::inverse(glm::lookAt(eye, target, up));
    d.yfov = yfov;
    return d;
}

/// A Lambertian sphere of radius 1 at the origin (analytic, or a closed convex UV-sphere mesh) under
/// a constant environment L.
Scene convexObjectUnderEnvironment(Rgb albedo, Rgb L, bool asMesh) {
    Scene scene;
    Material m;
    m.bsdf.baseColor = albedo;
    scene.materials.push_back(m);
    if (asMesh) scene.geometry.meshes.push_back(test::makeUvSphereMesh(Vec3f(0.f), 1.f, 24, 48, 0));
    else scene.geometry.spheres.push_back(Sphere{"ball", Vec3f(0.f), 1.f, 0});
    EnvironmentDesc env;
    env.color = L;
    env.intensity = 1.f;
    env.source = "constant";
    scene.environment = env;
    scene.finalize();
    return scene;
}

Film render(const Scene& scene, const std::string& integrator, int w, int h, int spp, uint64_t seed) {
    test::TestRender r = test::renderScene(scene, integrator, w, h, RenderOptions{.spp = spp, .seed = seed, .tileSize = 16});
    EXPECT_EQ(r.stats.nonFiniteDropped, 0u) << integrator;
    return std::move(r.film);
}

int sppFor(const std::string& name) { return name == "lt" ? 8192 : name == "bdpt" ? 64 : 128; }

}  // namespace

// Every point of a convex object sees only the environment (no part of it hides another), so a
// Lambertian surface of albedo a under constant radiance L reflects exactly a·L in every direction
// (irradiance π L, BRDF a/π) and the background is L: every integrator, each through its own
// strategies (pt: escaping BSDF rays; ptnee: + environment sampling, MIS; lt: light sub-paths from
// the environment's disk, camera rays for the background; bdpt: all of them).
TEST(EnvironmentFurnace, ConvexLambertianObjectUnderAConstantEnvironment) {
    const Rgb albedo(0.5f, 0.3f, 0.8f), L(1.f, 2.f, 0.5f);
    for (bool asMesh : {false, true}) {
        Scene scene = convexObjectUnderEnvironment(albedo, L, asMesh);
        // Filling the frame: at distance 3 the sphere subtends 19.5° (19.4° for the mesh's flat
        // facets); the frame's half-diagonal is 16°.
        scene.camera = lookAtCamera(Vec3f(0.3f, 0.4f, 3.f), Vec3f(0.f), 0.4f);
        for (const char* name : test::kIntegrators) {
            // Light tracing lands only ~1 in 5 of its paths in this frame and splats each with a
            // varying weight: 0.5% would take 16× its 2 M paths, so it is held to 1% (and 3 SE).
            bool lt = std::string(name) == "lt";
            Film film = render(scene, name, lt ? 16 : 24, lt ? 16 : 24, sppFor(name), 11);
            test::expectImageMean(film, albedo * L, lt ? 0.01 : 0.005, std::string(name) + (asMesh ? " mesh" : " sphere") + " object");
        }
        // Looking away from it: only the environment.
        scene.camera = lookAtCamera(Vec3f(0.f, 0.f, 3.f), Vec3f(0.f, 0.5f, 6.f), 0.8f);
        for (const char* name : test::kIntegrators) {
            Film film = render(scene, name, 16, 16, 4, 12);
            test::expectImageMean(film, L, 1e-5, std::string(name) + " background");
        }
    }
}

namespace {

/// A Lambertian square (side 2·half) in the plane y = 0 facing +y, seen head-on from above.
Scene planeUnderEnvironment(Rgb albedo, const Image* image, float half = 3.f) {
    Scene scene = test::diffusePlaneScene(albedo, half);
    EnvironmentDesc env;
    env.image = image;
    scene.environment = env;
    scene.finalize();
    scene.camera = lookAtCamera(Vec3f(0.f, 2.f, 0.f), Vec3f(0.f), 0.8f, Vec3f(0.f, 0.f, -1.f));
    return scene;
}

}  // namespace

// A diffuse plane seen head-on under an HDRI of known integral. The image is g(column) in the
// upper half (down to the first row below the horizon, so the bilinear lookup is exactly g(u) for
// every direction above the plane) and dimmer below. For a point on the plane
//     L = (a/π) ∫ L(ω) cos θ dω = (a/π) · (∫₀^2π g dφ) · ½ = a · mean(g),
// since the periodic piecewise-linear interpolant of g integrates to 2π · mean of its samples.
// g is far from uniform (one column 40× the rest), so importance sampling carries real weights.
TEST(EnvironmentFurnace, DiffusePlaneUnderAnHdriOfKnownIntegral) {
    const int w = 64, h = 32;
    auto g = [](int x) { return x == 20 ? Rgb(8.f, 6.f, 4.f) : Rgb(0.2f + 0.3f * float(x) / 64.f, 0.1f, 0.15f); };
    std::unique_ptr<Image> image = test::makeEnvironmentImage(w, h, [&](int x, int y) { return y <= h / 2 ? g(x) : 0.3f * g(x); });
    Rgb mean(0.f);
    for (int x = 0; x < w; ++x) mean += g(x) / float(w);
    const Rgb albedo(0.7f, 0.5f, 0.3f);
    Scene scene = planeUnderEnvironment(albedo, image.get());
    for (const char* name : test::kIntegrators) {
        bool lt = std::string(name) == "lt";
        // pt gets 1024 spp: its standard error (0.2%) then sits well inside the 0.5% bound.
        Film film = render(scene, name, 16, 16, lt ? 4096 : name == std::string("bdpt") ? 64 : name == std::string("pt") ? 1024 : 256, 21);
        test::expectImageMean(film, albedo * mean, lt ? 0.01 : 0.005, name);
    }
}

// The orientation convention (scene/environment.h): marks at known pixels of a black image appear
// where the convention puts them. Red at the −Z horizon (u = ¼, v = ½), blue at +X (the image
// centre), green at +Z (u = ¾), white along the top row (+Y), yellow a little right of the red
// (u ≈ 0.30, towards +X: right on screen for a camera looking down −Z, i.e. not mirrored).
TEST(EnvironmentOrientation, MarkedDirectionsRenderWhereTheConventionSays) {
    const int w = 64, h = 32;
    std::unique_ptr<Image> image = test::makeEnvironmentImage(w, h, [](int x, int y) {
        bool horizon = y == 15 || y == 16;
        if (y == 0) return Rgb(1.f);
        if (horizon && (x == 15 || x == 16)) return Rgb(100.f, 0.f, 0.f);
        if (horizon && (x == 31 || x == 32)) return Rgb(0.f, 0.f, 100.f);
        if (horizon && (x == 47 || x == 48)) return Rgb(0.f, 100.f, 0.f);
        if (horizon && x == 19) return Rgb(100.f, 100.f, 0.f);
        return Rgb(0.f);
    });
    Scene scene;
    scene.materials.push_back(Material{});
    scene.geometry.spheres.push_back(Sphere{"far below", Vec3f(0.f, -100.f, 0.f), 0.1f, 0});
    EnvironmentDesc env;
    env.image = image.get();
    scene.environment = env;
    scene.finalize();
    const int res = 33;
    const double centre = 16.5;  // in pixel coordinates: the middle of pixel 16
    // The value-weighted centroid of `weight` over the image (the marks are a few pixels wide).
    auto centroid = [&](const Film& film, const std::function<float(const Rgb&)>& weight, double& cx, double& cy) {
        double sum = 0.0, sx = 0.0, sy = 0.0;
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x) {
                double v = weight(film.pixel(x, y));
                sum += v;
                sx += v * (x + 0.5);
                sy += v * (y + 0.5);
            }
        cx = sum > 0 ? sx / sum : -1.0;
        cy = sum > 0 ? sy / sum : -1.0;
        return sum;
    };
    auto view = [&](Vec3f target, Vec3f up, float rotationDeg) {
        scene.environment->rotationDeg = rotationDeg;
        scene.finalize();
        scene.camera = lookAtCamera(Vec3f(0.f), target, 1.f, up);
        return render(scene, "pt", res, res, 16, 1);
    };
    auto red = [](const Rgb& c) { return c.r > c.g ? c.r - c.g : 0.f; };
    auto green = [](const Rgb& c) { return c.g > c.r ? c.g - c.r : 0.f; };
    auto blue = [](const Rgb& c) { return c.b; };
    auto yellow = [](const Rgb& c) { return std::min(c.r, c.g); };
    double x = 0, y = 0;
    Film front = view(Vec3f(0.f, 0.f, -1.f), Vec3f(0.f, 1.f, 0.f), 0.f);
    EXPECT_GT(centroid(front, red, x, y), 1.f);
    EXPECT_NEAR(x, centre, 0.5) << "red (u = 1/4) must be straight ahead along -Z";
    EXPECT_NEAR(y, centre, 0.5);
    EXPECT_LT(centroid(front, blue, x, y), 1e-3f) << "blue (+X) must be out of view";
    EXPECT_LT(centroid(front, green, x, y), 1e-3f) << "green (+Z) must be out of view";
    // Yellow (19.7° towards +X) lies right of red on screen, at the same height.
    EXPECT_GT(centroid(front, yellow, x, y), 1.f);
    EXPECT_GT(x, centre + 5.0) << "u increasing must turn right (towards +X), not mirrored";
    EXPECT_NEAR(y, centre, 0.5);

    Film right = view(Vec3f(1.f, 0.f, 0.f), Vec3f(0.f, 1.f, 0.f), 0.f);
    EXPECT_GT(centroid(right, blue, x, y), 1.f);
    EXPECT_NEAR(x, centre, 0.5) << "blue (the image centre) must lie along +X";
    Film back = view(Vec3f(0.f, 0.f, 1.f), Vec3f(0.f, 1.f, 0.f), 0.f);
    EXPECT_GT(centroid(back, green, x, y), 1.f);
    EXPECT_NEAR(x, centre, 0.5) << "green (u = 3/4) must lie along +Z";
    // Straight up is the top row (white): exactly 1 at the zenith, fading to black off it.
    Film up = view(Vec3f(0.f, 1.f, 0.f), Vec3f(0.f, 0.f, -1.f), 0.f);
    EXPECT_NEAR(up.pixel(16, 16).r, 1.f, 0.02f) << "the top row must be straight up";
    EXPECT_LT(up.pixel(0, 0).r, 0.1f);
    // Rotating by 90° about +Y (counter-clockwise from above) brings the image centre to −Z.
    Film rotated = view(Vec3f(0.f, 0.f, -1.f), Vec3f(0.f, 1.f, 0.f), 90.f);
    EXPECT_GT(centroid(rotated, blue, x, y), 1.f);
    EXPECT_NEAR(x, centre, 0.5) << "rotation 90 must bring +X to -Z";
    EXPECT_LT(centroid(rotated, red, x, y), 1e-3f);
}

namespace {

double relMse(const Film& film, double reference) {
    double sum = 0.0;
    for (int y = 0; y < film.height(); ++y)
        for (int x = 0; x < film.width(); ++x) {
            double v = luminance(film.pixel(x, y));
            sum += (v - reference) * (v - reference) / (reference * reference + 0.01);
        }
    return sum / (double(film.width()) * film.height());
}

}  // namespace

// Importance sampling works: a small, very bright sun (4 of 8192 pixels carrying ~95% of the
// light) over a dim sky, a diffuse plane. `pt` finds the sun only when a cosine-weighted bounce
// happens to hit it; `ptnee` samples it by luminance. Every pixel has the same expectation, so the
// reference is the mean of a long ptnee render. At equal samples ptnee's relative MSE must be at
// least 10× lower (measured ≈ 360×).
TEST(EnvironmentSampling, PtneeBeatsPtTenfoldWithASmallBrightSun) {
    const int w = 128, h = 64;
    std::unique_ptr<Image> image = test::makeEnvironmentImage(w, h, [](int x, int y) {
        bool sun = (x == 80 || x == 81) && (y == 16 || y == 17);
        return sun ? Rgb(20000.f, 18000.f, 15000.f) : Rgb(0.3f, 0.4f, 0.6f);
    });
    Scene scene = planeUnderEnvironment(Rgb(0.5f), image.get(), 10.f);
    double refMean[3], refSe[3];
    test::pixelMean(render(scene, "ptnee", 16, 16, 1024, 77), refMean, refSe);
    const double reference = luminance(Rgb(float(refMean[0]), float(refMean[1]), float(refMean[2])));
    const double pt = relMse(render(scene, "pt", 16, 16, 16, 78), reference);
    const double ptnee = relMse(render(scene, "ptnee", 16, 16, 16, 78), reference);
    std::cout << "relMSE at 16 spp: pt " << pt << ", ptnee " << ptnee << " (ratio " << pt / ptnee << ")" << std::endl;
    EXPECT_GT(pt, 10.0 * ptnee);
}

// Every integrator agrees bin by bin (tests/test_agreement.h) on an HDRI-lit scene of a diffuse, a
// glossy and a glass sphere on a diffuse floor, under a sky gradient with a soft sun. Light tracing
// cannot see the environment through glass (a delta vertex on the camera side) and is compared on
// the same scene without the glass sphere.
TEST(IntegratorAgreement, HdriLitDiffuseGlossyAndGlass) {
    std::unique_ptr<Image> image = test::makeEnvironmentImage(64, 32, [](int x, int y) {
        float dx = float(x) - 40.f, dy = float(y) - 9.f;
        float sun = std::exp(-(dx * dx + dy * dy) / 4.f) * 20.f;
        float sky = y < 16 ? 0.4f + 0.6f * float(y) / 16.f : 0.25f;
        return Rgb(sky * 0.7f + sun, sky * 0.8f + 0.9f * sun, sky + 0.8f * sun);
    });
    for (bool withGlass : {true, false}) {
        Scene scene;
        Material floor, diffuse, glossy, glass;
        floor.bsdf.baseColor = Rgb(0.6f);
        diffuse.bsdf.baseColor = Rgb(0.8f, 0.2f, 0.2f);
        glossy.bsdf.type = MaterialType::RoughConductor;
        glossy.bsdf.baseColor = Rgb(0.9f, 0.8f, 0.5f);
        glossy.bsdf.metallic = 1.f;
        glossy.bsdf.alpha = 0.1f;
        glass.bsdf.type = MaterialType::Dielectric;
        glass.bsdf.baseColor = Rgb(1.f);
        glass.bsdf.transmission = 1.f;
        glass.bsdf.ior = 1.5f;
        scene.materials = {floor, diffuse, glossy, glass};
        TriangleMesh quad;
        quad.name = "floor";
        quad.positions = {{-4.f, 0.f, -4.f}, {4.f, 0.f, -4.f}, {4.f, 0.f, 4.f}, {-4.f, 0.f, 4.f}};
        quad.triangles = {{0, 2, 1}, {0, 3, 2}};
        scene.geometry.meshes.push_back(quad);
        scene.geometry.spheres.push_back(Sphere{"diffuse", Vec3f(-1.1f, 0.5f, 0.f), 0.5f, 1});
        scene.geometry.spheres.push_back(Sphere{"glossy", Vec3f(0.f, 0.5f, -0.3f), 0.5f, 2});
        if (withGlass) scene.geometry.spheres.push_back(Sphere{"glass", Vec3f(1.1f, 0.5f, 0.2f), 0.5f, 3});
        EnvironmentDesc env;
        env.image = image.get();
        env.rotationDeg = 20.f;
        scene.environment = env;
        scene.finalize();
        scene.camera = lookAtCamera(Vec3f(0.f, 1.3f, 3.5f), Vec3f(0.f, 0.4f, 0.f), 0.8f);
        if (withGlass) test::expectIntegratorsAgree(scene, {{"ptnee", 16}, {"pt", 32}, {"bdpt", 8}}, 32, 32, 24);
        else test::expectIntegratorsAgree(scene, {{"ptnee", 32}, {"lt", 128}}, 32, 32, 24);
    }
}

// TESSERA_environment in a scene file: an EXR beside the scene (read linear, oriented and scaled as
// documented), a constant colour, negative and non-finite pixels read as 0, and the clear errors: a
// file outside the scene's folder, a missing file, contradictory or invalid members.
TEST(EnvironmentLoading, SceneExtensionReadsImagesBesideTheSceneOnly) {
    std::filesystem::path dir = test::tempDir("environment-load");
    std::filesystem::create_directories(dir / "scene");
    const int w = 8, h = 4;
    auto writeImage = [&](const std::filesystem::path& path, float fill) {
        std::vector<float> rgba(size_t(w * h * 4), fill);
        rgba[(size_t(2) * w + 6) * 4 + 0] = 5.f;  // one red-ish pixel at (6, 2)
        io::writeExr(path.string(), w, h, rgba.data(), {});
    };
    writeImage(dir / "scene" / "sky.exr", 0.5f);
    writeImage(dir / "outside.exr", 0.5f);
    writeImage(dir / "scene" / "negative.exr", -1.f);
    writeImage(dir / "scene" / "infinite.exr", std::numeric_limits<float>::infinity());
    auto sceneWith = [&](const std::string& environment) {
        std::string path = (dir / "scene" / "s.gltf").string();
        std::ofstream(path) << R"({"asset": {"version": "2.0"}, "extensionsUsed": ["TESSERA_environment"],
          "extensions": {"TESSERA_environment": )" + environment + R"(}, "scenes": [{"nodes": []}], "scene": 0})";
        return path;
    };
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(sceneWith(R"({"image": "sky.exr", "intensity": 2.0, "color": [1, 0.5, 1], "rotation": 45})"), warnings);
    ASSERT_TRUE(scene.environment && scene.environment->image);
    EXPECT_EQ(scene.environment->image->width(), w);
    EXPECT_FLOAT_EQ(scene.environment->rotationDeg, 45.f);
    const LightSet& lights = scene.lights();
    ASSERT_TRUE(lights.hasEnvironment());
    // The centre of pixel (1, 1) in the environment frame, turned by 45° into the world: 0.5 · 2 · color.
    const EnvironmentLight& env = lights.environment();
    Vec3f d = env.toWorld(EnvironmentLight::uvToDirection(Vec2f(1.5f / w, 1.5f / h)));
    Rgb L = lights.environmentLe(d);
    EXPECT_NEAR(L.r, 1.f, 1e-4f);
    EXPECT_NEAR(L.g, 0.5f, 1e-4f);
    Vec3f red = env.toWorld(EnvironmentLight::uvToDirection(Vec2f(6.5f / w, 2.5f / h)));
    EXPECT_NEAR(lights.environmentLe(red).r, 10.f, 1e-3f);

    Scene constant = loadGltfScene(sceneWith(R"({"color": [0.1, 0.2, 0.3]})"), warnings);
    ASSERT_TRUE(constant.environment);
    EXPECT_EQ(constant.lights().environmentLe(Vec3f(0.f, 1.f, 0.f)), Rgb(0.1f, 0.2f, 0.3f));

    auto expectError = [&](const std::string& environment, const std::string& needle) {
        try {
            loadGltfScene(sceneWith(environment), warnings);
            ADD_FAILURE() << environment << " loaded";
        } catch (const SceneError& e) {
            std::string msg = e.what();
            EXPECT_NE(msg.find("TESSERA_environment"), std::string::npos) << msg;
            EXPECT_NE(msg.find(needle), std::string::npos) << msg;
        }
    };
    expectError(R"({"image": "../outside.exr"})", "outside");
    Scene negative = loadGltfScene(sceneWith(R"({"image": "negative.exr"})"), warnings);
    EXPECT_EQ(negative.lights().environmentLe(Vec3f(0.f, 1.f, 0.f)), Rgb(0.f));
    EXPECT_NEAR(negative.lights().environmentLe(EnvironmentLight::uvToDirection(Vec2f(6.5f / w, 2.5f / h))).r, 5.f, 1e-4f);
    Scene infinite = loadGltfScene(sceneWith(R"({"image": "infinite.exr"})"), warnings);  // non-finite texels read as 0
    EXPECT_EQ(infinite.lights().environmentLe(Vec3f(0.f, 1.f, 0.f)), Rgb(0.f));
    expectError(R"({"image": "missing.exr"})", "not found");
    expectError(R"({"image": "sky.exr", "asset": "x.exr"})", "either");
    expectError(R"({"intensity": -1})", "intensity");
}

// The command line: --env R,G,B lights a scene that has none (the background is that colour),
// --env-intensity scales it, and the environment options alone on a scene without one are an error
// with exit code 2 and one line; --env overrides TESSERA_environment.
TEST(EnvironmentLoading, CommandLineEnvironmentOverridesTheScene) {
    std::filesystem::path dir = test::tempDir("environment-cli");
    auto run = [&](const std::string& scene, const std::string& args, std::string& err) {
        std::string cmd = "timeout 120 " + std::string(TESSERA_BINARY) + " render '" + scene + "' --quiet --no-png -o '" +
                          (dir / "out.exr").string() + "' --resolution 8x8 --spp 2 --integrator pt " + args + " 2> '" +
                          (dir / "err.txt").string() + "' > /dev/null";
        int status = std::system(cmd.c_str());
        std::ifstream in(dir / "err.txt");
        err.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    };
    // A scene of one small sphere, looking away from it: only the environment is seen.
    std::string scene = (dir / "s.gltf").string();
    std::ofstream(scene) << R"({"asset": {"version": "2.0"}, "extensionsUsed": ["TESSERA_sphere", "TESSERA_environment"],
      "extensionsRequired": ["TESSERA_sphere"],
      "extensions": {"TESSERA_environment": {"color": [9, 9, 9]}},
      "scenes": [{"nodes": [0, 1]}], "scene": 0,
      "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.01}}],
      "nodes": [{"camera": 0}, {"translation": [0, 0, 5], "extensions": {"TESSERA_sphere": {"radius": 0.5}}}]})";
    std::string err;
    ASSERT_EQ(run(scene, "--env 0.25,0.5,1 --env-intensity 2", err), 0) << err;
    io::Image image = io::readImage((dir / "out.exr").string());
    ASSERT_EQ(image.width, 8);
    EXPECT_NEAR(image.rgba[0], 0.5f, 1e-6f);
    EXPECT_NEAR(image.rgba[1], 1.f, 1e-6f);
    EXPECT_NEAR(image.rgba[2], 2.f, 1e-6f);
    ASSERT_EQ(run(scene, "--env-intensity 0.5", err), 0) << err;  // adjusts the scene's own (9, 9, 9)
    EXPECT_NEAR(io::readImage((dir / "out.exr").string()).rgba[0], 4.5f, 1e-5f);
    EXPECT_EQ(run(test::sourcePath("scenes/cornell-box/cornell-box.gltf"), "--env-rotate 30", err), 2);
    EXPECT_NE(err.find("--env-rotate and --env-intensity need an environment"), std::string::npos) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_EQ(run(scene, "--env 1,2", err), 2);
    EXPECT_NE(err.find("--env"), std::string::npos) << err;
}

// Light sub-paths from the environment and lt's camera rays keep renders bit-identical for any
// thread count.
TEST(EnvironmentDeterminism, LtAndBdptGiveTheSameBitsForOneAndTwoThreads) {
    std::unique_ptr<Image> image = test::spotAndGradientImage();
    Scene scene = convexObjectUnderEnvironment(Rgb(0.6f), Rgb(1.f), false);
    scene.environment->image = image.get();
    scene.finalize();
    scene.camera = lookAtCamera(Vec3f(0.f, 0.5f, 4.f), Vec3f(0.f), 0.9f);
    for (const char* name : {"lt", "bdpt", "ptnee"}) {
        std::vector<float> images[2];
        for (int threads : {1, 2}) {
            test::TestRender r = test::renderScene(scene, name, 24, 20, RenderOptions{.spp = 4, .threads = threads, .seed = 3, .tileSize = 16});
            images[threads - 1] = r.film.rgba();
        }
        EXPECT_EQ(images[0], images[1]) << name;
    }
}
