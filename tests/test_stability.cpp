// The stability findings of the convergence study (tools/study; its table is refs/study/stability.md),
// pinned as seeded numeric tests on the failure-mode scenes. Each test states what the study found
// and asserts it with a tolerance; every region is chosen from renders with one set of seeds and
// measured with renders of other seeds, so the selection's noise cannot leak into the measurement.
// Resolutions and sample counts are small, so the file runs in seconds.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include "integrators/bdpt.h"
#include "integrators/integrator.h"
#include "render/renderer.h"
#include "scene/gltf_loader.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

Film renderFilm(const Scene& scene, const Integrator& integrator, int w, int h, int spp, uint64_t seed) {
    auto accel = createAccel("embree", scene.geometry);
    test::TestRender r = test::renderScene(scene, *accel, integrator, w, h, RenderOptions{.spp = spp, .seed = seed});
    EXPECT_EQ(r.stats.nonFiniteDropped, 0u) << integrator.name();
    return std::move(r.film);
}

/// Per-pixel luminance (Rec. 709) of a render with the named integrator.
std::vector<double> renderLuminance(const Scene& scene, const char* name, int w, int h, int spp, uint64_t seed) {
    auto integrator = createIntegrator(name);
    return test::filmLuminance(renderFilm(scene, *integrator, w, h, spp, seed));
}

double sum(const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return s;
}

double sumOver(const std::vector<double>& v, const std::vector<bool>& mask) {
    double s = 0;
    for (size_t i = 0; i < v.size(); ++i)
        if (mask[i]) s += v[i];
    return s;
}

size_t count(const std::vector<bool>& mask) {
    size_t n = 0;
    for (bool b : mask) n += b;
    return n;
}

}  // namespace

// point-light-specular: a point light over a mirror and a glass sphere. The study: pt renders black
// (it cannot hit a delta light), ptnee misses the caustics (point light -> specular -> diffuse has no
// light-sampling connection), lt and bdpt (through t = 1) reproduce them. The caustic region is where
// lt is far brighter than ptnee (seeds 1, 2); lt (seed 3), bdpt (4), ptnee (5) and pt (6) are then
// measured there.
TEST(Stability, PointLightSpecularCausticsComeOnlyFromLightTracing) {
    Scene scene = test::loadSourceScene("scenes/point-light-specular/point-light-specular.gltf");
    const int w = 160, h = 120;
    std::vector<double> ltSel = renderLuminance(scene, "lt", w, h, 16, 1);
    std::vector<double> neeSel = renderLuminance(scene, "ptnee", w, h, 16, 2);
    double meanLt = sum(ltSel) / double(ltSel.size());
    std::vector<bool> caustic(ltSel.size());
    for (size_t i = 0; i < ltSel.size(); ++i) caustic[i] = ltSel[i] > 10.0 * neeSel[i] + 0.1 * meanLt;
    ASSERT_GT(count(caustic), 50u) << "no caustic region found";

    double lt = sumOver(renderLuminance(scene, "lt", w, h, 16, 3), caustic);
    double bdpt = sumOver(renderLuminance(scene, "bdpt", w, h, 8, 4), caustic);
    double nee = sumOver(renderLuminance(scene, "ptnee", w, h, 16, 5), caustic);
    std::vector<double> pt = renderLuminance(scene, "pt", w, h, 4, 6);
    std::cout << "caustic pixels " << count(caustic) << ", energy there: lt " << lt << ", bdpt " << bdpt
              << ", ptnee " << nee << ", pt (whole image) " << sum(pt) << "\n";
    EXPECT_EQ(sum(pt), 0.0) << "pt cannot hit a point light: exactly black";
    EXPECT_NEAR(lt / bdpt, 1.0, 0.10) << "lt and bdpt must agree on the caustics (10%)";
    EXPECT_LT(nee / lt, 0.10) << "ptnee must miss the caustics (under 10% of lt's energy there)";
}

// sds-caustic: a sphere light focused by a glass sphere onto a floor seen only in a mirror (light ->
// glass -> floor -> mirror -> camera). The study: bdpt gets this caustic from its s = 0 strategies
// alone (camera paths that hit the light), so it is as noisy there as ptnee's BSDF samples; a
// connection strategy (s >= 1) needs a non-delta vertex on each side, so it adds only the paths with
// one more diffuse bounce (a few per cent); lt, whose camera vertex would
// follow the mirror, sees none of it. The bdpt image minus its s = 0 strategies is the connections'
// share exactly (same seed, same random numbers: `BdptSettings::onlyS`).
// The SDS events are rare: with the shipped light a camera path reaches it through the glass about
// once in 10^5 samples (7-8 per 160x120 render at 32 spp, 2-3 of them in the shadow, with either
// sampler over 24 seeds), so a ratio of two renders would compare a handful of events and pass or
// fail by chance. The light is made 4x larger at equal power (test::enlargeSphereLight: 16x the
// events at 1/16 their value, the same paths and strategies).
TEST(Stability, SdsCausticComesOnlyFromBdptsUnidirectionalStrategies) {
    Scene scene = test::loadSourceScene("scenes/sds-caustic/sds-caustic.gltf");
    ASSERT_EQ(test::enlargeSphereLight(scene, 4.f), 1);
    const int w = 160, h = 120;
    BdptSettings s0Only;
    s0Only.onlyS = 0;
    BdptIntegrator bdptS0(s0Only), bdptAll;
    // Selection (seed 1): the glass sphere's shadow on the floor, where the connection strategies
    // (bdpt minus its s = 0 part) see nothing at all. Only light that went through the
    // glass (light -> glass -> floor, then mirror -> camera: SDS) lands there.
    std::vector<double> allSel = test::filmLuminance(renderFilm(scene, bdptAll, w, h, 8, 1));
    std::vector<double> s0Sel = test::filmLuminance(renderFilm(scene, bdptS0, w, h, 8, 1));
    std::vector<bool> sds(allSel.size());
    for (size_t i = 0; i < allSel.size(); ++i) sds[i] = allSel[i] - s0Sel[i] <= 0.0;
    ASSERT_GT(count(sds), 200u) << "no shadow region found";

    // Measurement (seed 2 for bdpt, 3 for ptnee, 4 for lt).
    std::vector<double> all = test::filmLuminance(renderFilm(scene, bdptAll, w, h, 32, 2));
    std::vector<double> s0 = test::filmLuminance(renderFilm(scene, bdptS0, w, h, 32, 2));
    double eAll = sumOver(all, sds), eS0 = sumOver(s0, sds);
    double eNee = sumOver(renderLuminance(scene, "ptnee", w, h, 32, 3), sds);
    // The shipped light: the enlarged one is in the camera's view.
    std::vector<double> lt = renderLuminance(test::loadSourceScene("scenes/sds-caustic/sds-caustic.gltf"), "lt", w, h, 8, 4);
    std::cout << "SDS pixels " << count(sds) << ", energy there: bdpt " << eAll << " (s = 0: " << eS0
              << ", connections " << eAll - eS0 << "), ptnee " << eNee << "; lt whole image " << sum(lt)
              << "; bdpt whole image " << sum(all) << "\n";
    // Measured 6.1% (7.3% with the independent sampler): connections only reach the shadow through a
    // second diffuse vertex (light -> lit floor -> glass -> shadow), the S-D-S part itself is s = 0's
    // alone.
    EXPECT_LT((eAll - eS0) / eAll, 0.10) << "connections must add under 10% in the SDS region";
    // Both are unbiased for these paths, with a few dozen events each at 32 spp (measured ratio 1.00,
    // 1.21 with the independent sampler): a factor 2.
    EXPECT_GT(eNee / eS0, 0.5) << "ptnee's BSDF samples through the glass reach the same paths as s = 0";
    EXPECT_LT(eNee / eS0, 2.0) << "ptnee's BSDF samples through the glass reach the same paths as s = 0";
    EXPECT_EQ(sum(lt), 0.0) << "lt cannot see anything through the mirror";
}

// tiny-light-10/100: the Cornell box with its light shrunk 10x and 100x at constant power. The
// study: pt's error grows roughly in proportion to 1/area (it must hit the light by chance), ptnee's
// hardly grows (it samples the light's area, whatever its size). Error = relMSE at 16 spp against a
// 512-spp ptnee render (its own error is ~1/32 of what it judges).
TEST(Stability, TinyLightBsdfSamplingErrorGrowsWithOneOverAreaNextEventEstimationsHardly) {
    const int w = 32, h = 32;
    const char* scenes[] = {"scenes/cornell-box/cornell-box.gltf", "scenes/tiny-light/tiny-light-10.gltf",
                            "scenes/tiny-light/tiny-light-100.gltf"};
    auto rgb = [&](const Film& f) {
        std::vector<double> v(size_t(w) * h * 3);
        for (int j = 0; j < h; ++j)
            for (int i = 0; i < w; ++i)
                for (int c = 0; c < 3; ++c) v[(size_t(j) * w + i) * 3 + c] = f.pixel(i, j)[c];
        return v;
    };
    auto relMse = [](const std::vector<double>& x, const std::vector<double>& r) {
        double e = 0;  // the definition of `tessera compare`: mean of (x - r)^2 / (r^2 + 0.01)
        for (size_t i = 0; i < x.size(); ++i) e += (x[i] - r[i]) * (x[i] - r[i]) / (r[i] * r[i] + 0.01);
        return e / double(x.size());
    };
    // pt's relMSE at 16 spp is a statistic of few light hits per pixel: one render's varies by
    // seed over 1.1-1.7 on the Cornell box (12 seeds, either sampler), so each figure is the mean
    // over kSeeds renders of their own seeds.
    constexpr int kSeeds = 4;
    double rel[2][3];
    const char* names[] = {"pt", "ptnee"};
    auto nee = createIntegrator("ptnee");
    for (int k = 0; k < 3; ++k) {
        Scene scene = test::loadSourceScene(scenes[k]);
        std::vector<double> ref = rgb(renderFilm(scene, *nee, w, h, 512, 100 + k));
        for (int m = 0; m < 2; ++m) {
            auto integrator = createIntegrator(names[m]);
            rel[m][k] = 0;
            for (int r = 0; r < kSeeds; ++r) rel[m][k] += relMse(rgb(renderFilm(scene, *integrator, w, h, 16, 7 + k + 10 * r)), ref) / kSeeds;
        }
    }
    double growPt = rel[0][2] / rel[0][0], growNee = rel[1][2] / rel[1][0];
    std::cout << "relMSE at 16 spp, light area 1, 1/10, 1/100: pt " << rel[0][0] << ", " << rel[0][1] << ", "
              << rel[0][2] << "; ptnee " << rel[1][0] << ", " << rel[1][1] << ", " << rel[1][2] << "; growth pt "
              << growPt << "x, ptnee " << growNee << "x\n";
    EXPECT_GT(rel[0][1] / rel[0][0], 3.0) << "pt: 10x smaller light, error up > 3x";
    EXPECT_GT(growPt, 20.0) << "pt: 100x smaller light, error up > 20x";
    EXPECT_LT(growNee, 3.0) << "ptnee: 100x smaller light, error up < 3x";
    EXPECT_GT(growPt, 10.0 * growNee) << "pt's error grows at least 10x more than ptnee's";
}

// door-ajar: all light reaches the camera's room through a door opened 12 degrees. The study: pt is
// hopeless (its paths must find the far room's light through the gap), ptnee's light samples are
// mostly occluded, bdpt's light sub-paths come through the gap and connect. Measured per sample at
// 80x60, 16 spp: relative variance (sum over pixels of Var / sum of mean^2, Var from two seeds)
// pt 1.6, ptnee 0.14, bdpt 0.038. Asserted with margin: pt >= 5x ptnee >= 2x bdpt.
TEST(Stability, DoorAjarBdptHasTheLowestVariancePerSample) {
    Scene scene = test::loadSourceScene("scenes/door-ajar/door-ajar.gltf");
    const int w = 80, h = 60, spp = 16;
    auto relVar = [&](const char* name, uint64_t seed) {
        auto integrator = createIntegrator(name);
        Film a = renderFilm(scene, *integrator, w, h, spp, seed), b = renderFilm(scene, *integrator, w, h, spp, seed + 1);
        double var = 0, meanSq = 0;
        for (int j = 0; j < h; ++j)
            for (int i = 0; i < w; ++i)
                for (int c = 0; c < 3; ++c) {
                    double x = a.pixel(i, j)[c], y = b.pixel(i, j)[c], m = 0.5 * (x + y);
                    var += 0.5 * (x - y) * (x - y);  // E[(x - y)^2] / 2 = Var of one render
                    meanSq += m * m;
                }
        return var / meanSq;
    };
    double pt = relVar("pt", 1), nee = relVar("ptnee", 3), bdpt = relVar("bdpt", 5);
    std::cout << "door-ajar relative variance at " << spp << " spp: pt " << pt << ", ptnee " << nee << ", bdpt " << bdpt
              << "\n";
    EXPECT_GT(pt / nee, 5.0) << "pt's variance per sample at least 5x ptnee's";
    EXPECT_GT(nee / bdpt, 2.0) << "ptnee's variance per sample at least 2x bdpt's";
}

// veach-mis: four glossy plates of increasing roughness under four sphere lights of decreasing size.
// The study (refs/study/stability.md): ptnee converges and is the best per unit of work; pt (BSDF
// sampling only: hopeless on the rough plates under the small lights) needs ~500x the work and lt
// (light sampling seen through sharp glossy reflections) ~80x; bdpt is within a small factor of
// ptnee. Pinned as relative variance per sample, weighted as relMSE, from two renders each at 64x48,
// 16 spp: measured pt 0.167, ptnee 0.043, lt 0.119, bdpt 0.041 (two renders see few of pt's and
// lt's rare large samples, which is why the ratios are far below the study's work ratios);
// asserted with margin: pt > 2x, lt > 1.5x ptnee, bdpt < 2x ptnee.
TEST(Stability, VeachMisOnlyMultipleImportanceSamplingHandlesEveryPlate) {
    Scene scene = test::loadSourceScene("scenes/veach-mis/veach-mis.gltf");
    const int w = 64, h = 48, spp = 16;
    auto relVar = [&](const char* name, uint64_t seed) {
        auto integrator = createIntegrator(name);
        Film a = renderFilm(scene, *integrator, w, h, spp, seed), b = renderFilm(scene, *integrator, w, h, spp, seed + 1);
        // Per pixel and channel Var / (mean^2 + 0.01), averaged: the relMSE weighting of the study
        // (a whole-image ratio would be dominated by the few pixels showing the lights).
        double rel = 0;
        for (int j = 0; j < h; ++j)
            for (int i = 0; i < w; ++i)
                for (int c = 0; c < 3; ++c) {
                    double x = a.pixel(i, j)[c], y = b.pixel(i, j)[c], m = 0.5 * (x + y);
                    rel += 0.5 * (x - y) * (x - y) / (m * m + 0.01);
                }
        return rel / double(w * h * 3);
    };
    double pt = relVar("pt", 11), nee = relVar("ptnee", 13), lt = relVar("lt", 15), bdpt = relVar("bdpt", 17);
    std::cout << "veach-mis relative variance at " << spp << " spp: pt " << pt << ", ptnee " << nee << ", lt " << lt
              << ", bdpt " << bdpt << "\n";
    EXPECT_GT(pt / nee, 2.0) << "BSDF sampling alone: at least 2x ptnee's variance";
    EXPECT_GT(lt / nee, 1.5) << "light tracing through glossy reflections: at least 1.5x ptnee's variance";
    EXPECT_LT(bdpt / nee, 2.0) << "bdpt's MIS keeps it within 2x of ptnee";
}

// furnace: a closed, emitting, diffuse sphere around the camera; every pixel is Le / (1 - a). The
// study: every integrator converges to it without bias (lt slowly: its camera connections from a
// closed sphere land on few pixels each). Pinned: each integrator's image mean per channel within
// 4 standard errors (from 8 independent renders) and 2% of the analytic value (lt: 10%).
TEST(Stability, FurnaceEveryIntegratorConvergesToTheAnalyticValue) {
    Scene scene = test::loadSourceScene("scenes/furnace/furnace.gltf");
    const double expected[3] = {1.0 / (1.0 - 0.5), 1.0 / (1.0 - 0.3), 1.0 / (1.0 - 0.7)};
    // 8 runs: a standard error from 4 (3 degrees of freedom) is too unsteady for a 4-sigma bound.
    const int w = 16, h = 16, spp = 8, runs = 8;
    for (const char* name : {"pt", "ptnee", "lt", "bdpt", "bdpt-balance"}) {
        auto integrator = createIntegrator(name);
        double mean[3] = {0, 0, 0}, sq[3] = {0, 0, 0};
        for (int k = 0; k < runs; ++k) {
            Film f = renderFilm(scene, *integrator, w, h, spp, 40 + uint64_t(k));
            for (int c = 0; c < 3; ++c) {
                double m = 0;
                for (int j = 0; j < h; ++j)
                    for (int i = 0; i < w; ++i) m += f.pixel(i, j)[c];
                m /= double(w * h);
                mean[c] += m / runs;
                sq[c] += m * m / runs;
            }
        }
        for (int c = 0; c < 3; ++c) {
            double se = std::sqrt(std::max(0.0, sq[c] - mean[c] * mean[c]) / (runs - 1));
            std::cout << "furnace " << name << " channel " << c << ": " << mean[c] << " +- " << se << " (expected "
                      << expected[c] << ")\n";
            EXPECT_NEAR(mean[c], expected[c], std::max(4.0 * se, 1e-9)) << name << " channel " << c;
            // lt's estimate is far noisier here (its splats land on few pixels), hence its wider bound.
            double relTol = std::string(name) == "lt" ? 0.10 : 0.02;
            EXPECT_NEAR(mean[c], expected[c], relTol * expected[c]) << name << " channel " << c;
        }
    }
}
