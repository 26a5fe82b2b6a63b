/// \file bench_accel_command.cpp
/// `tessera bench-accel INPUT...`: build time, memory and ray throughput of several acceleration
/// structures in one process, on identical ray sets, with interleaved repeats (run-to-run spread on
/// shared machines reaches 40%: only same-process ratios are meaningful) and medians.
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <atomic>
#include <iomanip>
#include <map>
#include <iostream>
#include <sstream>

#include "accel/bvh_accel.h"
#include "accel/kdtree_accel.h"
#include "app/bench_accel_processes.h"
#include "app/bench_clock.h"
#include "app/commands.h"
#include "core/error.h"
#include "geometry/instances.h"
#include "scene/scene_loader.h"
#include "validation/ray_sets.h"

namespace tessera::app {
namespace {

std::vector<std::string> splitList(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ','))
        if (!item.empty()) out.push_back(item);
    return out;
}

/// The benchmark's three ray sets, from the one generator validate-accel uses: primary rays in pixel
/// order, diffuse bounces from their hits in random order, shadow rays from their hits.
struct RaySets {
    std::vector<Ray> primary, diffuse, shadow;
    const std::vector<Ray>& get(const std::string& kind) const {
        return kind == "primary" ? primary : kind == "diffuse" ? diffuse : shadow;
    }
};

RaySets makeRays(const SceneGeometry& g, const Accel& oracle, const std::optional<CameraDesc>& camera, int resolution,
                 uint64_t seed) {
    size_t count = size_t(resolution) * size_t(resolution);
    return {generateRays(g, oracle, RayKind::Primary, count, seed, camera),
            generateRays(g, oracle, RayKind::Diffuse, count, seed, camera),
            generateRays(g, oracle, RayKind::Shadow, count, seed, camera)};
}

/// The query a ray set is traced with: closest hit (primary rays through intersectCoherent, as
/// the renderer traces its camera rays; diffuse rays through intersect) or any hit (shadow rays).
enum class Query { ClosestCoherent, Closest, Any };

inline bool trace(const Accel& accel, const Ray& r, Query q, Hit& h) {
    switch (q) {
    case Query::ClosestCoherent: return accel.intersectCoherent(r, h);
    case Query::Closest: return accel.intersect(r, h);
    case Query::Any: return accel.occluded(r);
    }
    return false;
}

/// One thread's loop over all rays (out of line, so that its frame and the traversal's stack lie
/// where the caller put the stack pointer).
__attribute__((noinline)) size_t traceAll(const Accel& accel, const std::vector<Ray>& rays, Query query) {
    size_t hits = 0;
    Hit h;
    for (const Ray& r : rays) hits += trace(accel, r, query, h);
    return hits;
}

/// traceAll with the stack pointer moved, first, to `pageOffset` bytes into a 4 KiB page (a layout
/// experiment: the traversal's stack then has the same page offset in every process, where ASLR
/// otherwise draws it afresh at each start); a negative offset leaves the stack where it is.
size_t traceAllAtStackOffset(const Accel& accel, const std::vector<Ray>& rays, Query query, int pageOffset) {
    if (pageOffset < 0) return traceAll(accel, rays, query);
    char probe = 0;
    const uintptr_t sp = reinterpret_cast<uintptr_t>(&probe);
    const size_t shift = (sp - uintptr_t(pageOffset)) & 4095u;
    volatile char* pad = static_cast<char*>(__builtin_alloca(shift + 64));
    pad[0] = probe;  // keeps the allocation
    return traceAll(accel, rays, query);
}

/// Seconds to trace all rays; `checksum` keeps the work. `cpuClock` (one thread only): the
/// thread's CPU time instead of the wall clock, so that time the thread spends descheduled on a
/// shared machine does not count.
double traceSeconds(const Accel& accel, const std::vector<Ray>& rays, Query query, int threads, size_t& checksum,
                    int stackPageOffset, bool cpuClock) {
    auto start = std::chrono::steady_clock::now();
    size_t hits = 0;
    if (threads == 1) {
        const double cpuStart = cpuSeconds(CLOCK_THREAD_CPUTIME_ID);
        hits = traceAllAtStackOffset(accel, rays, query, stackPageOffset);
        checksum += hits;
        if (cpuClock) return cpuSeconds(CLOCK_THREAD_CPUTIME_ID) - cpuStart;
    } else {
        std::atomic<size_t> total{0};
        auto body = [&] {
            tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 1024), [&](const tbb::blocked_range<size_t>& range) {
                size_t local = 0;
                Hit h;
                for (size_t i = range.begin(); i != range.end(); ++i) local += trace(accel, rays[i], query, h);
                total += local;
            });
        };
        if (threads > 0) tbb::task_arena(threads).execute(body);
        else body();
        hits = total;
        checksum += hits;
    }
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

nlohmann::json configJson(const BvhConfig& c) {
    return {{"traversalCost", c.traversalCost}, {"intersectionCost", c.intersectionCost}, {"sahBlockSize", c.sahBlockSize},
            {"maxLeafSize", c.maxLeafSize}, {"binCount", c.binCount}, {"parallelThreshold", c.parallelThreshold},
            {"maxSahDepth", c.maxSahDepth}, {"width", 8}, {"leaf", "Triangle4 watertight (Woop 2013)"}};
}

/// The k-d tree's build statistics (empty for other structures).
nlohmann::json kdStatsJson(const Accel& accel) {
    const auto* kd = dynamic_cast<const KdTreeAccel*>(&accel);
    if (!kd) return nlohmann::json::object();
    const KdBuildStats& s = kd->buildStats();
    return {{"innerNodes", s.innerNodes}, {"leaves", s.leaves}, {"emptyLeaves", s.emptyLeaves},
            {"referencesPerPrimitive", accel.stats().primitives ? double(s.references) / double(accel.stats().primitives) : 0.0},
            {"maxDepth", s.maxDepth}, {"depthLimit", s.depthLimit}, {"depthLimitHits", s.depthLimitHits},
            {"retractions", s.retractions}, {"eventsSwept", s.eventsSwept}, {"refsBinned", s.refsBinned}, {"sahCost", s.sahCost}};
}

nlohmann::json kdConfigJson(const KdConfig& c) {
    return {{"traversalCost", c.traversalCost}, {"intersectionCost", c.intersectionCost}, {"sahBlockSize", c.sahBlockSize},
            {"emptyBonus", c.emptyBonus}, {"emptyCutMinFraction", c.emptyCutMinFraction}, {"maxDepth", c.maxDepth}, {"maxBadRefines", c.maxBadRefines},
            {"perfectSplits", c.perfectSplits}, {"binnedAbove", c.binnedAbove}, {"binCount", c.binCount}};
}

/// `--complexity`: build times only, normalised by N·log2 N (Wald & Havran 2006 claim O(N log N) for
/// the k-d tree build: the ratio should stay about constant as N grows).
int runComplexity(const std::vector<std::string>& inputs, const std::vector<std::string>& accels, const AccelOptions& options,
                  int repeat, bool json, bool cpuClock) {
    nlohmann::json rows = nlohmann::json::array();
    if (!json) std::cout << "structure  primitives  build s (median of " << repeat << ")  ns / (N log2 N)\n";
    for (const std::string& input : inputs) {
        std::vector<std::string> warnings;
        std::optional<CameraDesc> camera;
        SceneGeometry g = loadGeometryFile(input, camera, warnings);
        double n = double(g.primitiveCount()), nLogN = n * std::log2(std::max(n, 2.0));
        for (const std::string& name : accels) {
            std::vector<double> seconds;
            nlohmann::json kdStats;
            for (int rep = 0; rep < repeat; ++rep) {
                const double cpuStart = cpuSeconds(CLOCK_PROCESS_CPUTIME_ID);
                auto accel = createAccel(name, g, options);
                seconds.push_back(cpuClock ? cpuSeconds(CLOCK_PROCESS_CPUTIME_ID) - cpuStart : accel->stats().buildSeconds);
                kdStats = kdStatsJson(*accel);
            }
            double s = median(seconds);
            rows.push_back({{"input", input}, {"structure", name}, {"primitives", g.primitiveCount()}, {"buildSeconds", s},
                            {"nsPerNLog2N", s / nLogN * 1e9}, {"kdStats", kdStats}});
            if (!json)
                std::cout << std::left << std::setw(11) << name << std::setw(12) << g.primitiveCount() << std::fixed
                          << std::setprecision(3) << std::setw(28) << s << std::setprecision(2) << s / nLogN * 1e9 << "   "
                          << input << (kdStats.empty() ? std::string() : " " + kdStats.dump()) << "\n";
        }
    }
    if (json) std::cout << nlohmann::json{{"threads", options.threads}, {"repeat", repeat}, {"kdConfig", kdConfigJson(KdConfig{})},
                                          {"builds", rows}}.dump(2) << std::endl;
    return 0;
}

struct BenchOptions {
    std::vector<std::string> inputs;
    std::string accels = "bvh,embree", rays = "primary,diffuse,shadow";
    int threads = 1, repeat = 5, resolution = 1024, processes = 1, stackPageOffset = -1;
    std::string clock = "cpu";
    /// Timings by CPU time: asked for, and meaningful (one thread).
    bool cpuClock() const { return clock == "cpu" && threads == 1; }
    double agreeWithin = 0.05;
    uint64_t seed = 1;
    bool json = false, complexity = false, flattened = false;
};

/// Bytes of the scene's own geometry data (vertices, attributes, indices, instance records): what
/// instancing saves beside the structures.
size_t geometryBytes(const SceneGeometry& g) {
    size_t b = g.spheres.size() * sizeof(Sphere) + g.instances.size() * sizeof(MeshInstance);
    for (const TriangleMesh& m : g.meshes)
        b += m.positions.size() * sizeof(Vec3f) + m.normals.size() * sizeof(Vec3f) + m.triangles.size() * sizeof(glm::uvec3) +
             (m.texcoords[0].size() + m.texcoords[1].size()) * sizeof(Vec2f) + m.tangents.size() * sizeof(Vec4f);
    for (const SceneGeometry& p : g.prototypes) b += geometryBytes(p);
    return b;
}

/// One structure's measurements on one input: every repeat's build time and rays/s per ray kind.
struct Measured {
    std::vector<double> buildSeconds;
    std::map<std::string, std::vector<double>> mrays;
    AccelStats stats;
    nlohmann::json kdStats;
    size_t geometryBytes = 0;
    bool instanced = false, flattened = false;
};

/// The JSON entry of one structure, with its text line printed unless `json`; `embree` points to
/// Embree's measurements when they were taken too (for the ratios).
nlohmann::json structureReport(const std::string& name, const std::vector<std::string>& kinds, const Measured& m,
                               const Measured* embree, size_t primitives, bool json) {
    nlohmann::json s = {{"buildSeconds", median(m.buildSeconds)}, {"buildSecondsRepeats", m.buildSeconds},
                        {"bytesPerPrimitive", primitives ? double(m.stats.memoryBytes) / double(primitives) : 0.0},
                        {"memoryBytes", m.stats.memoryBytes}, {"geometryBytes", m.geometryBytes}};
    std::ostringstream line;
    line << std::fixed << std::setprecision(3) << "  " << std::setw(8) << std::left << name << " build "
         << median(m.buildSeconds) << " s";
    if (embree) line << " (" << median(m.buildSeconds) / median(embree->buildSeconds) << "x embree)";
    line << std::setprecision(1) << ", " << s["bytesPerPrimitive"].get<double>() << " B/prim";
    if (m.instanced || m.flattened)
        line << " (structure " << double(m.stats.memoryBytes) / 1048576.0 << " MiB + geometry " << double(m.geometryBytes) / 1048576.0
             << " MiB)";
    for (const std::string& kind : kinds) {
        double mr = median(m.mrays.at(kind));
        s["mraysPerSecond"][kind] = mr;
        s["mraysPerSecondRepeats"][kind] = m.mrays.at(kind);  // every repeat, in order: the noise's structure
        line << std::setprecision(2) << ", " << kind << " " << mr << " Mrays/s";
        if (embree) {
            double ratio = mr / median(embree->mrays.at(kind));
            s["ratioToEmbree"][kind] = ratio;
            line << " (" << ratio << "x)";
        }
    }
    if (!m.kdStats.empty()) {
        s["kdStats"] = m.kdStats;
        line << "\n           " << m.kdStats.dump();
    }
    if (!json) std::cout << line.str() << "\n";
    return s;
}

/// Builds and traces every structure on one input, `repeat` times interleaved; prints a line per
/// structure (unless --json) and returns the input's JSON entry.
nlohmann::json benchInput(const std::string& input, const std::vector<std::string>& accels,
                          const std::vector<std::string>& kinds, const AccelOptions& options, const BenchOptions& opt) {
    std::vector<std::string> warnings;
    std::optional<CameraDesc> camera;
    SceneGeometry g = loadGeometryFile(input, camera, warnings);
    RaySets rays;
    {
        auto oracle = createAccel("embree", g, options);
        rays = makeRays(g, *oracle, camera, opt.resolution, opt.seed);
    }
    // Instanced input with --flattened: every structure also over the flattened copy (a world-space
    // copy of each instance), on the same rays, as "NAME-flat": memory and speed of the two.
    struct Run {
        std::string label, structure;
        const SceneGeometry* geometry;
    };
    std::vector<Run> runs;
    for (const std::string& name : accels) runs.push_back({name, name, &g});
    SceneGeometry flat;
    if (opt.flattened && !g.instances.empty()) {
        flat = InstanceFlattening(g).flatten();
        for (const std::string& name : accels) runs.push_back({name + "-flat", name, &flat});
    }
    std::map<std::string, Measured> measured;
    size_t checksum = 0;
    for (int rep = 0; rep < opt.repeat; ++rep) {
        for (const Run& run : runs) {  // interleaved: each repeat runs every structure
            const double cpuStart = cpuSeconds(CLOCK_PROCESS_CPUTIME_ID);
            auto accel = createAccel(run.structure, *run.geometry, options);
            const double buildCpu = cpuSeconds(CLOCK_PROCESS_CPUTIME_ID) - cpuStart;
            Measured& m = measured[run.label];
            m.geometryBytes = geometryBytes(*run.geometry);
            m.instanced = !run.geometry->instances.empty();
            m.flattened = run.geometry == &flat;
            m.stats = accel->stats();
            m.kdStats = kdStatsJson(*accel);
            // The CPU clock counts the whole createAccel (geometry gathering included) of all the
            // process's threads: with one thread, what the build cost; several threads' work adds up.
            m.buildSeconds.push_back(opt.cpuClock() ? buildCpu : accel->stats().buildSeconds);
            for (const std::string& kind : kinds) {
                const std::vector<Ray>& set = rays.get(kind);
                Query query = kind == "shadow" ? Query::Any : kind == "primary" ? Query::ClosestCoherent : Query::Closest;
                double s = traceSeconds(*accel, set, query, opt.threads, checksum, opt.stackPageOffset, opt.cpuClock());
                m.mrays[kind].push_back(double(set.size()) / s * 1e-6);
            }
        }
    }
    const size_t primitives = g.primitiveCount() + g.instancedPrimitiveCount();
    nlohmann::json entry = {{"input", input}, {"primitives", primitives}, {"instances", g.instances.size()},
                            {"prototypes", g.prototypes.size()},
                            {"rays", {{"primary", rays.primary.size()}, {"diffuse", rays.diffuse.size()}, {"shadow", rays.shadow.size()}}},
                            {"structures", nlohmann::json::object()}};
    if (!opt.json)
        std::cout << input << ": " << primitives << " primitives"
                  << (g.instances.empty() ? std::string()
                                          : " (" + std::to_string(g.instances.size()) + " instances of " + std::to_string(g.prototypes.size()) +
                                                " prototypes, " + std::to_string(g.primitiveCount()) + " flat)")
                  << "; rays primary " << rays.primary.size()
                  << ", diffuse " << rays.diffuse.size() << ", shadow " << rays.shadow.size() << "\n";
    const Measured* embree = measured.count("embree") ? &measured.at("embree") : nullptr;
    for (const Run& run : runs)
        entry["structures"][run.label] = structureReport(run.label, kinds, measured.at(run.label), embree, primitives, opt.json);
    entry["checksum"] = checksum;
    for (const std::string& w : warnings) printWarning(w);
    return entry;
}

}  // namespace

Runner addBenchAccelCommand(CLI::App& app) {
    auto opt = std::make_shared<BenchOptions>();
    CLI::App* cmd = app.add_subcommand("bench-accel", "Build time, memory and rays/s of acceleration structures on identical rays");
    cmd->add_option("INPUT", opt->inputs, "glTF scenes, PLY (.ply.gz) or OBJ meshes")->required();
    cmd->add_option("--accel", opt->accels, "comma-separated structures")->capture_default_str();
    cmd->add_option("--threads", opt->threads, "threads for building and tracing (0 = all)")->capture_default_str();
    cmd->add_option("--rays", opt->rays, "ray kinds: primary, diffuse, shadow")->capture_default_str();
    cmd->add_option("--repeat", opt->repeat, "interleaved repeats (the median is reported)")->capture_default_str();
    cmd->add_option("--resolution", opt->resolution, "primary rays: a square image of this many pixels a side")->capture_default_str();
    cmd->add_option("--seed", opt->seed, "seed of the ray sets")->capture_default_str();
    cmd->add_flag("--json", opt->json, "print one JSON object instead of text");
    cmd->add_flag("--flattened", opt->flattened,
                  "instanced scenes: also every structure over the flattened copy (NAME-flat), for memory and speed");
    cmd->add_flag("--complexity", opt->complexity, "build times only, with build time / (N log2 N) per input");
    cmd->add_option("--processes", opt->processes,
                    "run the benchmark in this many fresh processes, one after another, and report every figure as "
                    "the median over them with its range and spread (a process's memory layout can slow one ray kind "
                    "by 25-40% for its whole life)")
        ->capture_default_str();
    cmd->add_option("--clock", opt->clock,
                    "cpu: with --threads 1, time builds by the process's CPU time and tracing by the thread's, so "
                    "that time spent descheduled on a shared machine does not count; wall: the wall clock (always "
                    "with several threads)")
        ->check(CLI::IsMember({"cpu", "wall"}))
        ->capture_default_str();
    cmd->add_option("--stack-page-offset", opt->stackPageOffset,
                    "layout experiment (one thread): trace with the stack pointer at this byte offset into a 4 KiB "
                    "page, the same in every process (-1: where ASLR put it)")
        ->capture_default_str();
    cmd->add_option("--agree-within", opt->agreeWithin,
                    "with --processes: the largest spread (max - min) / median a ratio to embree may have to count as "
                    "reproducible (reported)")
        ->capture_default_str();
    return [opt] {
        std::vector<std::string> accels = splitList(opt->accels), kinds = splitList(opt->rays);
        for (const std::string& k : kinds)
            if (k != "primary" && k != "diffuse" && k != "shadow") throw InputError("--rays: unknown kind '" + k + "'");
        AccelOptions options;
        options.threads = opt->threads;
        if (opt->processes > 1) {
            if (opt->complexity) throw InputError("bench-accel: --processes does not apply to --complexity");
            std::vector<std::string> args{"bench-accel", "--json", "--accel", opt->accels, "--rays", opt->rays,
                                          "--threads", std::to_string(opt->threads), "--repeat", std::to_string(opt->repeat),
                                          "--resolution", std::to_string(opt->resolution), "--seed", std::to_string(opt->seed)};
            if (opt->flattened) args.push_back("--flattened");
            args.insert(args.end(), {"--clock", opt->clock});
            if (opt->stackPageOffset >= 0) args.insert(args.end(), {"--stack-page-offset", std::to_string(opt->stackPageOffset)});
            args.insert(args.end(), opt->inputs.begin(), opt->inputs.end());
            return runBenchProcesses(args, opt->processes, opt->agreeWithin, opt->json);
        }
        if (opt->complexity) return runComplexity(opt->inputs, accels, options, opt->repeat, opt->json, opt->cpuClock());
        nlohmann::json report = {{"threads", opt->threads}, {"repeat", opt->repeat}, {"resolution", opt->resolution}, {"stackPageOffset", opt->stackPageOffset},
                                 {"clock", opt->cpuClock() ? "cpu" : "wall"},
                                 {"bvhConfig", configJson(BvhConfig{})},
                                 {"kdConfig", kdConfigJson(KdConfig{})}, {"inputs", nlohmann::json::array()}};
        if (!opt->json) std::cout << "config: threads " << opt->threads << ", repeat " << opt->repeat << ", clock " << (opt->cpuClock() ? "cpu" : "wall") << ", bvh "
                                  << configJson(BvhConfig{}).dump() << ", kdtree "
                                  << kdConfigJson(KdConfig{}).dump() << "\n";
        for (const std::string& input : opt->inputs)
            report["inputs"].push_back(benchInput(input, accels, kinds, options, *opt));
        if (opt->json) std::cout << report.dump(2) << std::endl;
        return 0;
    };
}

}  // namespace tessera::app
