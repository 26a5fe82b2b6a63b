/// \file bench_photons_command.cpp
/// `tessera bench-photons INPUT`: the two photon structures of accel/photon_map.h (Jensen's k-d
/// tree, SmallVCM's hashed grid) built over the same points and queried at the same places, in one
/// process with interleaved repeats and medians (bench_clock.h), so that the ratio between them is
/// meaningful on a shared machine. Photons are where diffuse bounces from the camera's view land
/// (validate-accel's diffuse ray set traced with Embree): points on surfaces, dense where the
/// scene folds, as light sub-paths leave them; the queries are where camera rays land (the visible
/// points a photon-mapping integrator looks up).
#include <nlohmann/json.hpp>

#include <iomanip>
#include <iostream>

#include "accel/accel.h"
#include "accel/photon_map.h"
#include "app/bench_clock.h"
#include "app/commands.h"
#include "core/error.h"
#include "core/thread_pool.h"
#include "scene/scene_loader.h"
#include "validation/ray_sets.h"

namespace tessera::app {
namespace {

struct BenchPhotonsOptions {
    std::string input;
    size_t photons = 1000000, queries = 262144;
    float radiusFactor = 0.0015f;
    int threads = 1, repeat = 5;
    uint64_t seed = 1;
    bool json = false;
};

/// Where `count` rays of `kind` first hit the scene (rays that miss are left out).
std::vector<Vec3f> hitPoints(const SceneGeometry& g, const Accel& embree, RayKind kind, size_t count, uint64_t seed,
                             const std::optional<CameraDesc>& camera) {
    std::vector<Vec3f> points;
    for (const Ray& r : generateRays(g, embree, kind, count, seed, camera)) {
        Hit h;
        if (embree.intersect(r, h)) points.push_back(r.o + h.t * r.d);
    }
    return points;
}

/// Finds, for every query, the points within `radius`; returns the total (the work's checksum).
template <class Structure>
size_t queryAll(const Structure& s, const std::vector<Vec3f>& queries, float radius) {
    size_t found = 0;
    for (const Vec3f& x : queries) s.forEachWithin(x, radius, [&](uint32_t) { ++found; });
    return found;
}

int runBenchPhotons(const BenchPhotonsOptions& opt) {
    std::vector<std::string> warnings;
    std::optional<CameraDesc> camera;
    SceneGeometry g = loadGeometryFile(opt.input, camera, warnings);
    for (const std::string& w : warnings) printWarning(w);
    auto embree = createAccel("embree", g);
    const std::vector<Vec3f> photons = hitPoints(g, *embree, RayKind::Diffuse, opt.photons, opt.seed, camera);
    const std::vector<Vec3f> queries = hitPoints(g, *embree, RayKind::Primary, opt.queries, opt.seed + 1, camera);
    if (photons.empty() || queries.empty()) throw InputError(opt.input + ": no ray hits the scene: nothing to benchmark");
    const float radius = opt.radiusFactor * glm::length(g.bounds().diagonal());
    ThreadPool pool(opt.threads);
    // The clock: the process's CPU time for builds (all threads), the thread's for the serial queries.
    const clockid_t buildClock = CLOCK_PROCESS_CPUTIME_ID, queryClock = CLOCK_THREAD_CPUTIME_ID;
    std::vector<double> kdBuild, gridBuild, kdQuery, gridQuery;
    size_t kdFound = 0, gridFound = 0, kdBytes = 0, gridBytes = 0;
    for (int rep = 0; rep < opt.repeat; ++rep) {
        PhotonKdTree kd;
        PhotonHashGrid grid;
        double t0 = cpuSeconds(buildClock);
        kd.build(photons, &pool);
        double t1 = cpuSeconds(buildClock);
        grid.build(photons, radius, &pool);
        double t2 = cpuSeconds(buildClock);
        kdBuild.push_back(t1 - t0);
        gridBuild.push_back(t2 - t1);
        double q0 = cpuSeconds(queryClock);
        kdFound = queryAll(kd, queries, radius);
        double q1 = cpuSeconds(queryClock);
        gridFound = queryAll(grid, queries, radius);
        double q2 = cpuSeconds(queryClock);
        kdQuery.push_back(q1 - q0);
        gridQuery.push_back(q2 - q1);
        kdBytes = kd.memoryBytes();
        gridBytes = grid.memoryBytes();
    }
    if (kdFound != gridFound) {
        printError("the k-d tree found " + std::to_string(kdFound) + " photons and the hash grid " + std::to_string(gridFound) +
                   ": the structures disagree");
        return 1;
    }
    const double n = double(photons.size()), q = double(queries.size());
    if (opt.json) {
        nlohmann::json j = {{"input", opt.input}, {"photons", photons.size()}, {"queries", queries.size()}, {"radius", radius},
                            {"threads", opt.threads}, {"repeat", opt.repeat}, {"photonsPerQuery", double(kdFound) / q},
                            {"kdtree", {{"buildSeconds", median(kdBuild)}, {"querySeconds", median(kdQuery)}, {"bytesPerPhoton", double(kdBytes) / n}}},
                            {"hashgrid", {{"buildSeconds", median(gridBuild)}, {"querySeconds", median(gridQuery)}, {"bytesPerPhoton", double(gridBytes) / n}}}};
        std::cout << j.dump(2) << "\n";
        return 0;
    }
    std::cout << std::fixed << std::setprecision(3) << opt.input << ": " << photons.size() << " photons, " << queries.size()
              << " queries of radius " << std::setprecision(5) << radius << " (" << std::setprecision(1) << double(kdFound) / q
              << " photons each), build on " << opt.threads << " thread(s), medians of " << opt.repeat << " repeats (CPU time)\n";
    auto line = [&](const char* name, const std::vector<double>& build, const std::vector<double>& query, size_t bytes) {
        std::cout << "  " << std::left << std::setw(9) << name << std::right << std::setprecision(1) << " build "
                  << median(build) * 1e9 / n << " ns/photon, query " << median(query) * 1e9 / q << " ns/query, "
                  << double(bytes) / n << " B/photon\n";
    };
    line("kdtree", kdBuild, kdQuery, kdBytes);
    line("hashgrid", gridBuild, gridQuery, gridBytes);
    std::cout << std::setprecision(2) << "  hashgrid / kdtree time: build " << median(gridBuild) / median(kdBuild) << "x, query "
              << median(gridQuery) / median(kdQuery) << "x\n";
    return 0;
}

}  // namespace

Runner addBenchPhotonsCommand(CLI::App& app) {
    auto opt = std::make_shared<BenchPhotonsOptions>();
    CLI::App* cmd = app.add_subcommand("bench-photons", "Build and query times of the photon k-d tree and hash grid on one scene");
    cmd->add_option("input", opt->input, "glTF scene, PLY or OBJ mesh")->required();
    cmd->add_option("--photons", opt->photons, "diffuse rays whose hits are the photons")->capture_default_str();
    cmd->add_option("--queries", opt->queries, "camera rays whose hits are the queries")->capture_default_str();
    cmd->add_option("--radius-factor", opt->radiusFactor, "query radius as a fraction of the scene's diagonal (SmallVCM: 0.003 of its radius)")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    cmd->add_option("--threads", opt->threads, "threads of the builds (queries run on one)")->capture_default_str()->check(CLI::Range(1, 1024));
    cmd->add_option("--repeat", opt->repeat, "interleaved repeats (medians are reported)")->capture_default_str()->check(CLI::Range(1, 1000));
    cmd->add_option("--seed", opt->seed, "seed of the ray sets")->capture_default_str();
    cmd->add_flag("--json", opt->json, "print JSON");
    return [opt] { return runBenchPhotons(*opt); };
}

}  // namespace tessera::app
