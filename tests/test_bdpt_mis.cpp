// BDPT bookkeeping: the densities the random walks store are the ones the MIS code recomputes, and
// for random full paths the weights of all strategies that generate the same path sum to one and
// equal the brute-force p_s^β / Σ p_i^β (Veach 1997, eq. 9.13 / 10.10).
#include <gtest/gtest.h>

#include "integrators/bdpt_connect.h"
#include "integrators/vcm.h"
#include "scene/gltf_loader.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

void expectRelNear(double a, double b, double rel, const std::string& what) {
    EXPECT_LE(std::abs(a - b), rel * std::max(std::abs(a), std::abs(b)) + 1e-30) << what << ": " << a << " vs " << b;
}

/// What a random walk stored equals the densities recomputed from its vertices.
void expectStoredDensitiesMatch(const RenderContext& ctx, const std::vector<PathVertex>& sub, const std::string& what) {
    for (size_t j = 1; j < sub.size(); ++j) {
        float fwd = pdfNextA(ctx, j >= 2 ? &sub[j - 2] : nullptr, sub[j - 1], sub[j]);
        expectRelNear(sub[j].pdfFwdA, fwd, 1e-3, what + " pdfFwdA");
        if (j + 2 < sub.size()) expectRelNear(sub[j].pdfRevA, pdfNextA(ctx, &sub[j + 2], sub[j + 1], sub[j]), 1e-3, what + " pdfRevA");
    }
}

/// The full path x0 … xk of strategy split s as the walks would have produced it: the light
/// sub-path x0 … x(s−1) (`ys`) and the camera sub-path xk … xs (`zs`), with the densities pL (from
/// the light side) and pE (from the camera side) of every vertex.
void splitPath(const std::vector<PathVertex>& x, const std::vector<double>& pL, const std::vector<double>& pE, int s,
               const BsdfParams& lightMaterial, std::vector<PathVertex>& ys, std::vector<PathVertex>& zs) {
    const int k = int(x.size()) - 1;
    ys.assign(x.begin(), x.begin() + s);
    zs.clear();
    for (int i = 0; i < s; ++i) ys[size_t(i)].pdfFwdA = float(pL[size_t(i)]), ys[size_t(i)].pdfRevA = float(pE[size_t(i)]);
    for (int i = k; i >= s; --i) {
        PathVertex v = x[size_t(i)];
        v.pdfFwdA = float(pE[size_t(i)]);
        v.pdfRevA = float(pL[size_t(i)]);
        zs.push_back(v);
    }
    if (s == 0 && !x[0].atInfinity) {
        // The camera sub-path's end lies on the light as an ordinary surface hit (an escaped camera
        // ray's end is the light vertex at infinity itself).
        PathVertex& e = zs.back();
        e.type = VertexType::Surface;
        e.bsdf = lightMaterial;
        e.ns = e.ng;
        e.woWorld = glm::normalize(x[1].p - x[0].p);
    }
}

/// For the full path x0 … xk (x0 on a light, xk the lens): the weight of every strategy equals the
/// brute-force p_s^β / Σ p_i^β, and the weights sum to one. False (nothing checked) when some
/// density along the path is zero. A delta light (`lightIsDelta`: point, spot, directional) cannot
/// be hit, so the strategy s = 0 does not exist for it. `withMerges`: VCM's weights, the k − 1
/// merges at the interior vertices joining the connections (p_VM,i = p_(i+1) · p←(x_i) · η,
/// Georgiev et al. 2012), with η chosen so that merges and connections weigh alike.
bool checkWeightsOfPath(const RenderContext& ctx, const std::vector<PathVertex>& x, const BsdfParams& lightMaterial,
                        bool lightIsDelta = false, bool withMerges = false) {
    const int k = int(x.size()) - 1;
    // p→(x_i): density from the light side; p←(x_i): from the camera side (x_k is the lens).
    std::vector<double> pL(size_t(k + 1), 0.0), pE(size_t(k + 1), 0.0);
    pL[0] = pdfLightOriginA(ctx, x[0]);
    for (int i = 1; i <= k - 1; ++i) pL[size_t(i)] = pdfNextA(ctx, i >= 2 ? &x[size_t(i - 2)] : nullptr, x[size_t(i - 1)], x[size_t(i)]);
    for (int i = k - 1; i >= 0; --i) pE[size_t(i)] = pdfNextA(ctx, i + 2 <= k ? &x[size_t(i + 2)] : nullptr, x[size_t(i + 1)], x[size_t(i)]);
    for (int i = 0; i < k; ++i)
        if (!(pL[size_t(i)] > 0.0 && pE[size_t(i)] > 0.0)) return false;  // e.g. x1 behind the one-sided light

    const double eta = withMerges ? 1.0 / pE[size_t(k / 2)] : 0.0;
    for (MisHeuristic h : {MisHeuristic::Power, MisHeuristic::Balance}) {
        double beta = h == MisHeuristic::Power ? 2.0 : 1.0;
        std::vector<double> ps(size_t(k + 1)), psMerge(size_t(k + 1), 0.0);
        auto connectionDensity = [&](int s) {
            double p = 1.0;
            for (int i = 0; i < s; ++i) p *= pL[size_t(i)];
            for (int i = s; i < k; ++i) p *= pE[size_t(i)];
            return p;
        };
        double sumPs = 0.0;
        for (int s = lightIsDelta ? 1 : 0; s <= k; ++s) {  // t = k + 1 − s ≥ 1
            ps[size_t(s)] = std::pow(connectionDensity(s), beta);
            sumPs += ps[size_t(s)];
        }
        for (int i = 1; withMerges && i < k; ++i) {
            psMerge[size_t(i)] = std::pow(connectionDensity(i + 1) * pE[size_t(i)] * eta, beta);
            sumPs += psMerge[size_t(i)];
        }
        double sumW = 0.0;
        std::vector<PathVertex> ys, zs;
        for (int s = lightIsDelta ? 1 : 0; s <= k; ++s) {
            int t = k + 1 - s;
            splitPath(x, pL, pE, s, lightMaterial, ys, zs);
            bdptMisPrefixes(ctx, ys, zs, h, eta);
            float w = bdptStrategyWeight(ctx, ys, zs, s, t, s > 0 ? &ys.back() : nullptr, &zs.back(), h, eta);
            expectRelNear(w, ps[size_t(s)] / sumPs, 2e-3, "weight of (s=" + std::to_string(s) + ", t=" + std::to_string(t) + ")");
            sumW += w;
        }
        for (int i = 1; withMerges && i < k; ++i) {
            // The merge at x_i: the light sub-path x0 … x_i leaves its photon there, the camera
            // sub-path xk … x_i ends on it.
            std::vector<PathVertex> photonPath;
            splitPath(x, pL, pE, i + 1, lightMaterial, photonPath, zs);
            photonPath.back().woWorld = directionTo(photonPath.back(), photonPath[size_t(i - 1)]);
            bdptMisPrefixes(ctx, photonPath, {}, h, eta);
            std::vector<VcmPhoton> photons;
            std::vector<Vec3f> positions;
            vcmPhotonsOfPath(ctx, photonPath, h, eta, photons, positions);
            if (photons.empty() || photons.back().depth != uint32_t(i)) {
                ADD_FAILURE() << "no photon at light vertex " << i;
                continue;
            }
            splitPath(x, pL, pE, i, lightMaterial, ys, zs);
            bdptMisPrefixes(ctx, {}, zs, h, eta);
            const PathVertex& xi = zs.back();
            SurfaceBsdf bsdf(xi.bsdf, xi.ns, xi.ng, SurfaceBsdf::Use::EvalOnly);
            float w = vcmMergeWeight(ctx, photons.back(), zs, int(zs.size()), bsdf, eta, h);
            expectRelNear(w, psMerge[size_t(i)] / sumPs, 2e-3, "weight of the merge at x" + std::to_string(i));
            sumW += w;
        }
        EXPECT_NEAR(sumW, 1.0, 1e-4) << "path of " << k + 1 << " vertices";
    }
    return true;
}

}  // namespace

namespace {

void checkCornellPaths(bool withMerges) {
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(test::sourcePath("scenes/cornell-box/cornell-box.gltf"), warnings);
    auto accel = createAccel("embree", scene.geometry);
    Camera cam(*scene.camera, 32, 32);
    RenderContext ctx{scene, *accel, cam, -1};
    uint32_t lightMaterial = 0;
    for (const TriangleMesh& m : scene.geometry.meshes)
        if (scene.materials[m.materialId].isEmissive()) lightMaterial = m.materialId;

    std::vector<PathVertex> camera, light;
    int pathsChecked = 0;
    for (uint32_t trial = 0; trial < 400 && pathsChecked < 150; ++trial) {
        Sampler sampler(Vec2i(int(trial % 32), int(trial / 32)), trial, 17);
        traceCameraSubpath(ctx, Vec2f(float(trial % 32) + 0.5f, float((trial / 32) % 32) + 0.5f), sampler, -1, camera);
        traceLightSubpath(ctx, sampler, -1, light);
        expectStoredDensitiesMatch(ctx, camera, "camera");
        expectStoredDensitiesMatch(ctx, light, "light");
        if (!light.empty()) expectRelNear(light[0].pdfFwdA, pdfLightOriginA(ctx, light[0]), 1e-5, "light origin");

        // A full path x0 … xk: x0 the light sub-path's origin, then the camera sub-path reversed.
        if (camera.size() < 2 || light.empty()) continue;
        std::vector<PathVertex> x;
        x.push_back(light[0]);
        for (size_t j = camera.size(); j-- > 0;) x.push_back(camera[j]);
        if (checkWeightsOfPath(ctx, x, scene.materials[lightMaterial].bsdf, false, withMerges)) ++pathsChecked;
    }
    EXPECT_GE(pathsChecked, 50);
}

}  // namespace

TEST(BdptMis, StoredDensitiesMatchAndWeightsOfAllStrategiesSumToOne) { checkCornellPaths(false); }

// VCM (integrators/vcm.h): connections and merges under one weight, the merges' from the photon's
// stored sums and the camera BSDF's densities at the merge; η = 0 is bdpt's weight.
TEST(VcmMis, WeightsOfConnectionsAndMergesSumToOneAndEqualBruteForce) { checkCornellPaths(true); }

// connectBdpt takes a connection's densities from the BSDFs it built to evaluate f; they must be
// exactly those connectionDensities evaluates from the vertices (the weights' one definition), for
// every strategy that draws no random numbers (general connections, s = 0), with either heuristic,
// in a diffuse box and in one with mirror and glass objects (delta vertices on the sub-paths).
TEST(BdptMis, ConnectionsWeightWithTheDensitiesTheVerticesDefine) {
    for (const char* name : {"cornell-box", "cornell-box-specular"}) {
        std::vector<std::string> warnings;
        Scene scene = loadGltfScene(test::sourcePath(std::string("scenes/") + name + "/" + name + ".gltf"), warnings);
        auto accel = createAccel("embree", scene.geometry);
        Camera cam(*scene.camera, 32, 32);
        RenderContext ctx{scene, *accel, cam, -1};
        std::vector<PathVertex> camera, light;
        int compared = 0;
        for (uint32_t trial = 0; trial < 1000; ++trial) {
            Sampler sampler(Vec2i(int(trial % 32), int(trial / 32)), trial, 41);
            traceCameraSubpath(ctx, Vec2f(float(trial % 32) + 0.5f, float((trial / 32) % 32) + 0.5f), sampler, -1, camera);
            traceLightSubpath(ctx, sampler, -1, light);
            for (MisHeuristic h : {MisHeuristic::Power, MisHeuristic::Balance}) {
                bdptMisPrefixes(ctx, light, camera, h);
                for (int t = 2; t <= int(camera.size()); ++t)
                    for (int s = 0; s <= int(light.size()); ++s) {
                        if (s == 1) continue;  // resamples its light point
                        ConnectionResult r = connectBdpt(ctx, light, camera, s, t, sampler, h);
                        if (isBlack(r.L)) continue;
                        float w = bdptStrategyWeight(ctx, light, camera, s, t, s > 0 ? &light[size_t(s - 1)] : nullptr,
                                                     &camera[size_t(t - 1)], h);
                        EXPECT_EQ(r.weight, w) << name << " (s=" << s << ", t=" << t << ")";
                        ++compared;
                    }
            }
        }
        std::cout << name << ": " << compared << " weights compared\n";
        EXPECT_GE(compared, 1000) << name;
    }
}

TEST(BdptMis, DeltaVerticesAreSkippedAndTheRestSumToOne) {
    // Path y0 – y1 – [mirror y2] – z1 – z0 expressed with densities only: strategies connecting at
    // the mirror vertex are impossible, the others must still sum to one.
    std::vector<MisVertex> all = {{0.5f, 0.2f, false}, {1.3f, 0.7f, false}, {0.f, 0.f, true}, {2.1f, 0.4f, false}};
    // Full path x0..x3 plus the camera x4. For split s, light = x0..x(s−1), camera = x4..x(s).
    double sum = 0.0;
    for (int s = 0; s <= 4; ++s) {
        std::vector<MisVertex> light(all.begin(), all.begin() + s), camera;
        camera.push_back({1.f, 0.f, false});  // lens
        for (int i = 3; i >= s; --i) camera.push_back({all[size_t(i)].pdfRevA, all[size_t(i)].pdfFwdA, all[size_t(i)].delta});
        bool possible = !(s >= 1 && all[size_t(s - 1)].delta) && !(s <= 3 && all[size_t(s)].delta);
        float w = bdptMisWeight(light, camera, false, MisHeuristic::Power);
        if (possible) sum += w;
    }
    EXPECT_NEAR(sum, 1.0, 1e-5);
}

// Paths that start at infinity (pbrt-v3 §16.3.1's infinite lights): the environment (as the origin
// of a light sub-path, or the end of a camera ray that escaped) and a directional light. Their
// first vertex has a direction, not a position: its density is in solid angle and the next
// vertex's is the emission disk's 1/(π r²) times the cosine there. The weights of all strategies
// must still sum to one and equal the brute-force ratios, in the Cornell box (open at the front,
// so camera rays escape) lit by its area light, a constant environment and a sun.
namespace {

void checkPathsAtInfinity(bool withMerges) {
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(test::sourcePath("scenes/cornell-box/cornell-box.gltf"), warnings);
    EnvironmentDesc env;
    env.color = Rgb(0.4f, 0.5f, 0.6f);
    scene.environment = env;
    // Shining into the box through its open front (the camera looks down +z into it).
    scene.directionalLights.push_back({glm::normalize(Vec3f(0.2f, -0.3f, 1.f)), Rgb(3.f)});
    scene.finalize();
    const LightSet& lights = scene.lights();
    ASSERT_TRUE(lights.hasEnvironment());
    auto accel = createAccel("embree", scene.geometry);
    Camera cam(*scene.camera, 32, 32);
    RenderContext ctx{scene, *accel, cam, -1};
    BsdfParams unused;

    std::vector<PathVertex> camera, light;
    int fromEnvironment = 0, escaped = 0, fromDirectional = 0;
    for (uint32_t trial = 0; trial < 3000 && (fromEnvironment < 40 || escaped < 40 || fromDirectional < 40); ++trial) {
        Sampler sampler(Vec2i(int(trial % 32), int(trial / 32)), trial, 29);
        traceCameraSubpath(ctx, Vec2f(float(trial % 32) + 0.5f, float((trial / 32) % 32) + 0.5f), sampler, -1, camera);
        traceLightSubpath(ctx, sampler, -1, light);
        expectStoredDensitiesMatch(ctx, camera, "camera");
        expectStoredDensitiesMatch(ctx, light, "light");
        if (!light.empty()) expectRelNear(light[0].pdfFwdA, pdfLightOriginA(ctx, light[0]), 1e-5, "light origin");
        if (camera.size() < 2) continue;
        std::vector<PathVertex> x;
        if (camera.back().atInfinity) {
            // The camera ray escaped: the path starts at the environment vertex it ends with.
            if (camera.size() < 3) continue;  // the environment seen directly has one strategy
            for (size_t j = camera.size(); j-- > 0;) x.push_back(camera[j]);
            if (checkWeightsOfPath(ctx, x, unused, false, withMerges)) ++escaped;
            continue;
        }
        if (light.empty() || !light[0].atInfinity) continue;
        x.push_back(light[0]);
        for (size_t j = camera.size(); j-- > 0;) x.push_back(camera[j]);
        bool directional = lights.isDelta(light[0].lightIndex);
        if (checkWeightsOfPath(ctx, x, unused, directional, withMerges)) ++(directional ? fromDirectional : fromEnvironment);
    }
    EXPECT_GE(fromEnvironment, 40);
    EXPECT_GE(escaped, 40);
    EXPECT_GE(fromDirectional, 40);
}

}  // namespace

TEST(BdptMis, WeightsSumToOneOnPathsFromTheEnvironmentAndADirectionalLight) { checkPathsAtInfinity(false); }
TEST(VcmMis, WeightsSumToOneOnPathsFromTheEnvironmentAndADirectionalLight) { checkPathsAtInfinity(true); }
