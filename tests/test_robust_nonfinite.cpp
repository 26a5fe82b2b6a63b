// Non-finite samples: the scheduler drops them (and non-finite splats), counts them and names the
// first one by (sample, y, x) whatever the thread count; --debug-pixel replays a sample exactly as
// the render took it.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "io/image_output.h"
#include "render/debug_pixel.h"
#include "render/renderer.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

/// The value of `name=` in a trace line (the first component of a triple), or NaN when absent.
double traceField(const std::string& line, const std::string& name) {
    size_t at = line.find(" " + name + "=");
    if (at == std::string::npos) return std::nan("");
    size_t v = at + name.size() + 2;
    if (line[v] == '(') ++v;
    return std::strtod(line.c_str() + v, nullptr);
}

/// Counts of what a --debug-pixel trace holds, with every density and MIS weight checked.
struct TraceSummary {
    int vertexLines = 0, strategyLines = 0, bsdfPdfs = 0, lightPdfs = 0, subpathPdfs = 0;
};

TraceSummary checkTrace(const std::string& trace) {
    TraceSummary sum;
    std::istringstream in(trace);
    std::string line;
    while (std::getline(in, line)) {
        bool vertex = line.rfind("  vertex ", 0) == 0;
        bool subpath = line.rfind("  camera vertex ", 0) == 0 || line.rfind("  light vertex ", 0) == 0;
        bool strategy = line.rfind("  strategy s=", 0) == 0;
        if (vertex) {
            ++sum.vertexLines;
            // Every vertex line names where it is and the throughput that reached it.
            EXPECT_TRUE(std::isfinite(traceField(line, "p"))) << line;
            EXPECT_GT(traceField(line, "beta"), 0.0) << line;
        }
        if (subpath) {
            // Sub-path vertices carry their forward area density (> 0: every vertex was sampled).
            double pdfFwdA = traceField(line, "pdfFwdA");
            EXPECT_TRUE(std::isfinite(pdfFwdA) && pdfFwdA > 0.0) << line;
            ++sum.subpathPdfs;
        }
        if (strategy) {
            ++sum.strategyLines;
            double w = traceField(line, "misW");
            if (!std::isnan(w)) {
                EXPECT_TRUE(w >= 0.0 && w <= 1.0) << line;
            }
        }
        // A diffuse scene: every BSDF and light density the integrators print is finite and > 0.
        // (The BSDF density of a light sample behind the surface is 0: it is only checked finite.)
        double lightBsdfPdfW = traceField(line, "lightBsdfPdfW");
        if (!std::isnan(lightBsdfPdfW)) {
            EXPECT_TRUE(std::isfinite(lightBsdfPdfW) && lightBsdfPdfW >= 0.0) << line;
        }
        for (const char* name : {"bsdfPdfW", "lightPdfW", "emissionPdfLightW"}) {
            double v = traceField(line, name);
            if (std::isnan(v)) continue;
            EXPECT_TRUE(std::isfinite(v) && v > 0.0) << name << " in " << line;
            if (std::string(name) == "bsdfPdfW") ++sum.bsdfPdfs;
            if (std::string(name) == "lightPdfW") ++sum.lightPdfs;
        }
        for (const char* name : {"lightMisW", "emissionMisW"}) {
            double w = traceField(line, name);
            if (!std::isnan(w)) {
                EXPECT_TRUE(w > 0.0 && w <= 1.0) << name << " in " << line;
            }
        }
    }
    return sum;
}

/// Returns 0.25 everywhere except NaN at chosen (pixel, sample index) pairs, and splats +Inf from
/// one more; everything else a plain constant, so the expected film is known exactly.
class PoisonedIntegrator : public Integrator {
public:
    std::string_view name() const override { return "poisoned"; }
    Rgb sample(const RenderContext& ctx, Vec2i pixel, Vec2f raster, Sampler& sampler, SplatSink& splats) const override {
        // The sampler has given the jitter; draw once more to learn the sample index back from a
        // fresh stream is impossible, so the index is found by matching the jitter (tests only).
        for (const SampleId& p : nanAt)
            if (pixel.x == p.x && pixel.y == p.y && matches(pixel, raster, p.sample)) return Rgb(std::nanf(""), 0.f, 0.f);
        if (pixel.x == infSplatFrom.x && pixel.y == infSplatFrom.y && matches(pixel, raster, infSplatFrom.sample))
            splats.splat(ctx.camera.width(), ctx.camera.height(), Vec2f(0.5f), Rgb(kInfinity));
        return Rgb(0.25f);
    }
    std::vector<SampleId> nanAt;
    SampleId infSplatFrom;
    uint64_t seed = 0;

private:
    bool matches(Vec2i pixel, Vec2f raster, uint32_t s) const {
        Sampler ref(pixel, s, seed);
        Vec2f r = Vec2f(float(pixel.x), float(pixel.y)) + ref.get2D();
        return r == raster;
    }
};

/// Runs one `--debug-pixel` replay: its JSON report (stdout) and its trace (stderr, kept in
/// `tracePath`). Throws when the command cannot start or fails (gtest reports the test as failed).
struct Replay {
    nlohmann::json json;
    std::string trace;
};
Replay runReplay(const std::string& command, const std::filesystem::path& tracePath) {
    std::string cmd = command + " 2> '" + tracePath.string() + "'";
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) throw std::runtime_error("cannot run " + cmd);
    std::string out;
    char buf[4096];
    while (size_t n = std::fread(buf, 1, sizeof buf, p)) out.append(buf, n);
    if (pclose(p) != 0) throw std::runtime_error("failed: " + cmd);
    std::ifstream in(tracePath);
    return {nlohmann::json::parse(out), std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>())};
}

}  // namespace

TEST(NonFinite, DroppedCountedAndFirstNamedForAnyThreadCount) {
    Scene scene = test::closedSphere(Rgb(0.5f), Rgb(1.f), false);
    auto accel = createAccel("embree", scene.geometry);
    Camera camera(*scene.camera, 40, 24);
    RenderContext ctx{scene, *accel, camera, -1};
    PoisonedIntegrator integrator;
    integrator.seed = 9;
    // The first by (sample, y, x) is (30,1) sample 2, though (3,20) sample 2 comes first in tile order.
    integrator.nanAt = {{3, 20, 2}, {30, 1, 2}, {7, 7, 5}, {0, 0, 3}};
    integrator.infSplatFrom = {39, 23, 1};
    for (int threads : {1, 2}) {
        Film film(40, 24);
        RenderOptions opt{.spp = 8, .threads = threads, .seed = 9, .tileSize = 8};
        RenderStats stats = renderImage(ctx, integrator, film, opt);
        EXPECT_EQ(stats.nonFiniteDropped, 5u) << threads;
        ASSERT_TRUE(stats.firstNonFinite.has_value());
        EXPECT_EQ(stats.firstNonFinite->x, 39);
        EXPECT_EQ(stats.firstNonFinite->y, 23);
        EXPECT_EQ(stats.firstNonFinite->sample, 1u) << "the Inf splat (sample 1) comes before every NaN (samples 2+)";
        for (float v : film.rgba()) ASSERT_TRUE(std::isfinite(v));
        EXPECT_EQ(film.sampleCount(30, 1), 7u);
        EXPECT_EQ(film.sampleCount(1, 1), 8u);
        EXPECT_EQ(film.pixel(30, 1).r, 0.25f);  // the NaN sample left no trace in the mean
    }
    integrator.infSplatFrom = {-1, -1, 0};
    Film film(40, 24);
    RenderOptions opt{.spp = 8, .seed = 9};
    RenderStats stats = renderImage(ctx, integrator, film, opt);
    ASSERT_TRUE(stats.firstNonFinite.has_value());
    EXPECT_EQ(stats.firstNonFinite->x, 30);
    EXPECT_EQ(stats.firstNonFinite->y, 1);
    EXPECT_EQ(stats.firstNonFinite->sample, 2u);

    // The replay of that sample finds the same NaN, and says where it arose.
    std::ostringstream trace;
    SampleReplay r = replaySample(ctx, integrator, *stats.firstNonFinite, 9, kDefaultSampler, trace);
    EXPECT_FALSE(r.finite);
    EXPECT_NE(trace.str().find("first non-finite value: the returned radiance"), std::string::npos) << trace.str();
    SampleReplay fine = replaySample(ctx, integrator, SampleId{30, 1, 3}, 9, kDefaultSampler, trace);
    EXPECT_TRUE(fine.finite);
    EXPECT_EQ(fine.radiance, Rgb(0.25f));
}

TEST(DebugPixel, ReplayEqualsTheOneSampleRenderBitForBit) {
    namespace fs = std::filesystem;
    fs::path dir = test::tempDir("debug-pixel");
    const std::string scene = test::sourcePath("scenes/cornell-box/cornell-box.gltf");
    const std::string base = std::string(TESSERA_BINARY) + " render '" + scene + "' --quiet --resolution 40x30 --seed 5 ";
    for (const char* integrator : {"ptnee", "pt"}) {
        fs::path exr = dir / (std::string(integrator) + ".exr");
        int status = std::system((base + "--integrator " + integrator + " --spp 1 --no-png -o '" + exr.string() + "'").c_str());
        ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
        io::Image image = io::readImage(exr.string());
        int nonZero = 0;
        TraceSummary total;
        for (auto [x, y] : {std::pair{20, 15}, {3, 27}, {33, 4}, {11, 9}, {39, 29}, {0, 0}}) {
            auto [j, trace] = runReplay(base + "--integrator " + integrator + " --json --debug-pixel " + std::to_string(x) +
                                            "," + std::to_string(y) + ",0",
                                        dir / "trace.txt");
            EXPECT_TRUE(j["finite"].get<bool>());
            EXPECT_GT(j["rays"].get<int>(), 0);
            TraceSummary t = checkTrace(trace);
            // A camera ray that hits the box makes at least one vertex; one record per vertex.
            if (trace.find("ray 1: o=") != std::string::npos && trace.find("-> hit") != std::string::npos) {
                EXPECT_GE(t.vertexLines, 1) << trace;
            }
            EXPECT_EQ(size_t(t.vertexLines), j["trace_records"].get<size_t>()) << trace;
            total.vertexLines += t.vertexLines;
            total.bsdfPdfs += t.bsdfPdfs;
            total.lightPdfs += t.lightPdfs;
            for (int c = 0; c < 3; ++c) {
                float replay = j["radiance"][c].get<float>();
                float rendered = image.rgba[4 * (size_t(y) * 40 + x) + c];
                EXPECT_EQ(std::memcmp(&replay, &rendered, sizeof(float)), 0)
                    << integrator << " pixel (" << x << "," << y << ") channel " << c << ": " << replay << " vs " << rendered;
                nonZero += replay != 0.f;
            }
        }
        // Next-event estimation lights almost every pixel at 1 spp; pure path tracing rarely does.
        // The densities are counted against the vertices the six replays made (how long the paths
        // are depends on the sampler's draws): in this all-diffuse box every vertex samples the
        // BSDF, and in ptnee a light, but perhaps one (a vertex on the light itself).
        std::cout << integrator << ": " << total.vertexLines << " vertices, " << total.bsdfPdfs << " BSDF and "
                  << total.lightPdfs << " light samples\n";
        if (std::string(integrator) == "ptnee") {
            EXPECT_GT(nonZero, 6) << "most of these pixels see lit surfaces";
            EXPECT_GE(total.lightPdfs, total.vertexLines - 1) << "ptnee samples a light at (almost) every vertex";
        }
        EXPECT_GE(total.vertexLines, 3) << integrator << ": three of the six pixels see the box";
        EXPECT_GE(total.bsdfPdfs, total.vertexLines - 1) << integrator << ": a BSDF sample at (almost) every vertex";
    }
    // Light tracing and BDPT: sub-path vertices with their area densities, and per (s,t) strategy
    // the contribution (and for BDPT the MIS weight).
    for (const char* integrator : {"lt", "bdpt"}) {
        auto [j, trace] = runReplay(base + "--integrator " + integrator + " --json --debug-pixel 20,15,0", dir / "trace.txt");
        EXPECT_TRUE(j["finite"].get<bool>());
        TraceSummary t = checkTrace(trace);
        EXPECT_GE(t.subpathPdfs, 1) << trace;
        EXPECT_GE(t.strategyLines, 1) << trace;
        EXPECT_EQ(size_t(t.subpathPdfs + t.strategyLines), j["trace_records"].get<size_t>()) << trace;
        if (std::string(integrator) == "bdpt") {
            EXPECT_NE(trace.find("  camera vertex 1 "), std::string::npos) << trace;
            EXPECT_NE(trace.find(" misW="), std::string::npos) << trace;
        }
    }
    std::ifstream in(dir / "trace.txt");
    std::string trace((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(trace.find("replaying pixel (20,15) sample 0 seed 5 with bdpt"), std::string::npos) << trace;
    EXPECT_NE(trace.find("ray 1: o="), std::string::npos) << trace;
    // Out of the image: a clear error, exit 2.
    int bad = std::system((base + "--debug-pixel 40,0,0 2>/dev/null >/dev/null").c_str());
    ASSERT_TRUE(WIFEXITED(bad));
    EXPECT_EQ(WEXITSTATUS(bad), 2);
}
