/// \file batch_command.cpp
/// `tessera batch JOBS.json`: many renders in one run (app/batch_jobs.h has the file format). A scene
/// used by several jobs is loaded once and its acceleration structure built once per kind; a job
/// that fails is reported and the batch goes on; a JSON summary lists every job.
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>

#include "accel/accel.h"
#include "app/batch_jobs.h"
#include "app/commands.h"
#include "app/render_job.h"
#include "app/scene_options.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "render/interrupt.h"
#include "render/progress.h"

namespace tessera::app {
namespace {

struct BatchArgs {
    std::string jobsFile, jsonSummary;
    int threads = 0;
    bool json = false, quiet = false, failFast = false;
};

double secondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// The options that make a loaded scene: jobs that agree on them share one Scene.
std::string sceneKey(const RenderJob& j) {
    std::error_code ec;
    std::filesystem::path canonical = std::filesystem::weakly_canonical(j.scene, ec);
    return (ec ? j.scene : canonical.string()) + "\n" + (j.allowExternalFiles ? "external" : "contained") + "\n" +
           std::to_string(j.maxMemoryGiB) + "\n" + j.env + "\n" + (j.envRotate ? std::to_string(*j.envRotate) : "-") + "\n" +
           (j.envIntensity ? std::to_string(*j.envIntensity) : "-");
}

/// Scenes and their acceleration structures, each loaded or built once (a failure too: the jobs
/// after it fail with the same reason at no cost) and dropped after the last job that needs it.
class SceneCache {
public:
    SceneCache(const BatchFile& file, int threads, bool quiet) : threads_(threads), quiet_(quiet) {
        for (const BatchJob& j : file.jobs) lastUse_[sceneKey(j.render)] = j.index;
    }

    struct Entry {
        std::optional<Scene> scene;
        std::string error;  ///< the load failed: why
        std::map<std::string, std::unique_ptr<Accel>> accels;
        std::map<std::string, std::string> accelErrors;
    };

    /// The job's scene, loaded with its environment options applied; `loaded` says whether this call loaded it.
    const Scene& scene(const RenderJob& job, bool& loaded) {
        Entry& e = entries_[sceneKey(job)];
        loaded = !e.scene && e.error.empty();
        if (loaded) {
            ++loads_;
            auto start = std::chrono::steady_clock::now();
            try {
                Scene scene = loadScene(job);
                applyEnvironmentOptions(job, scene);
                e.scene.emplace(std::move(scene));
            } catch (const InputError& err) {
                e.error = err.what();
            }
            log("loaded " + job.scene + (e.error.empty() ? "" : " (failed)") + " in " + formatDuration(secondsSince(start)));
        }
        if (!e.error.empty()) throw InputError(e.error);
        return *e.scene;
    }

    /// The job's acceleration structure over its scene (scene() first); `built` as `loaded` above.
    const Accel& accel(const RenderJob& job, bool& built) {
        Entry& e = entries_.at(sceneKey(job));
        const std::string name = accelName(job);
        built = !e.accels.count(name) && !e.accelErrors.count(name);
        if (built) {
            ++builds_;
            try {
                AccelOptions options;
                options.threads = threads_;
                std::unique_ptr<Accel> accel = createAccel(name, e.scene->geometry, options);
                log("built " + name + " over " + job.scene + " in " + formatDuration(accel->stats().buildSeconds));
                e.accels[name] = std::move(accel);
            } catch (const InputError& err) {
                e.accelErrors[name] = err.what();
            }
        }
        if (auto it = e.accelErrors.find(name); it != e.accelErrors.end()) throw InputError(it->second);
        return *e.accels.at(name);
    }

    /// Frees what no job after `job` needs.
    void release(const BatchJob& job) {
        std::string key = sceneKey(job.render);
        if (lastUse_[key] == job.index) entries_.erase(key);
    }

    int loads() const { return loads_; }
    int builds() const { return builds_; }

private:
    void log(const std::string& line) const {
        if (!quiet_) std::cerr << "tessera batch: " << line << std::endl;
    }

    int threads_;
    bool quiet_;
    std::map<std::string, size_t> lastUse_;
    std::map<std::string, Entry> entries_;
    int loads_ = 0, builds_ = 0;
};

/// The camera a job asks for among the ones its scene file places.
std::optional<CameraDesc> pickCamera(const BatchJob& job, const Scene& scene) {
    const CameraChoice& c = job.camera;
    if (c.kind == CameraChoice::Kind::Scene) return scene.camera;
    const SceneCamera* found = nullptr;
    for (const SceneCamera& sc : scene.cameras)
        if (!found && (c.kind == CameraChoice::Kind::Index ? sc.index == c.index : sc.name == c.name)) found = &sc;
    for (const SceneCamera& sc : scene.cameras)  // a name may also be the name of the node that places the camera
        if (!found && c.kind == CameraChoice::Kind::Name && sc.nodeName == c.name) found = &sc;
    if (!found) {
        std::string have;
        for (const SceneCamera& sc : scene.cameras)
            have += (have.empty() ? "" : ", ") + std::to_string(sc.index) + (sc.name.empty() ? "" : " '" + sc.name + "'") +
                    (sc.nodeName.empty() ? "" : " (node '" + sc.nodeName + "')");
        throw InputError(job.render.scene + ": no camera " +
                         (c.kind == CameraChoice::Kind::Index ? std::to_string(c.index) : "named '" + c.name + "'") +
                         " (the file places " + (have.empty() ? "none" : have) + ")");
    }
    if (!found->desc) throw InputError(found->problem);
    return found->desc;
}

/// What the summary records of one job.
struct JobRecord {
    std::string status = "not run";  ///< ok, failed, interrupted, not run
    std::string error;
    std::optional<RenderJobResult> result;
    std::optional<RenderSettings> settings;
    OutputPaths out;
    double seconds = 0.0;
    bool sceneLoaded = false, accelBuilt = false;
};

/// Loads (or reuses) the scene and structure, checks the job, renders it.
void runJob(const BatchJob& job, size_t count, SceneCache& cache, JobRecord& rec) {
    const RenderJob& r = job.render;
    const Scene& scene = cache.scene(r, rec.sceneLoaded);
    RenderSettings s = resolveRenderSettings(r, scene);
    JobPlan plan = planRenderJob(r, s, resolveCamera(r, pickCamera(job, scene)));
    const Accel& accel = cache.accel(r, rec.accelBuilt);
    if (interruptFlag().load()) return;  // Ctrl-C while loading or building: render nothing more
    rec.settings = s;
    std::string label = "job " + std::to_string(job.index + 1) + "/" + std::to_string(count) + " " +
                        (job.name.empty() ? stem(r.scene) : job.name);
    rec.result = runRenderJob(r, plan, scene, accel, label);
    rec.out = plan.out;
    rec.status = rec.result->stats.interrupted ? "interrupted" : "ok";
}

/// The batch's remaining time from what it has measured: time-bounded jobs take their time, the
/// others the mean wall time of the fixed-spp jobs done so far. Unknown before one is done.
std::optional<double> estimateRemaining(const BatchFile& file, const std::vector<JobRecord>& records, size_t next) {
    double sppSeconds = 0.0;
    int sppJobs = 0;
    for (size_t i = 0; i < next; ++i)
        if (records[i].status == "ok" && file.jobs[i].render.timeLimit <= 0) {
            sppSeconds += records[i].seconds;
            ++sppJobs;
        }
    double left = 0.0;
    for (size_t i = next; i < file.jobs.size(); ++i) {
        if (file.jobs[i].render.timeLimit > 0) {
            left += file.jobs[i].render.timeLimit;
        } else {
            if (sppJobs == 0) return std::nullopt;
            left += sppSeconds / sppJobs;
        }
    }
    return left;
}

nlohmann::json jobJson(const BatchJob& job, const JobRecord& rec) {
    nlohmann::json j = {{"index", job.index}, {"scene", job.render.scene}, {"status", rec.status}, {"seconds", rec.seconds},
                        {"scene_loaded", rec.sceneLoaded}, {"accel_built", rec.accelBuilt}};
    if (!job.name.empty()) j["name"] = job.name;
    if (!rec.error.empty()) j["error"] = rec.error;
    if (rec.result) {
        const RenderStats& st = rec.result->stats;
        j["outputs"] = rec.out.png.empty() ? nlohmann::json{{"exr", rec.out.exr}} : nlohmann::json{{"exr", rec.out.exr}, {"png", rec.out.png}};
        j["integrator"] = rec.settings->integrator;
        j["accel"] = rec.result->accel;
        j["spp"] = st.sppCompleted;
        j["samples"] = st.samples;
        j["render_seconds"] = st.seconds;
        j["resolution"] = {rec.settings->width, rec.settings->height};
        j["seed"] = rec.settings->seed;
        j["nonfinite_dropped"] = st.nonFiniteDropped;
        if (!rec.result->checkpoint.empty()) j["checkpoint"] = rec.result->checkpoint;
    }
    return j;
}

void writeSummaryFile(const std::string& path, const nlohmann::json& summary) {
    writeFileAtomically(path, "JSON summary", [&](const std::string& tmp) {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        out << summary.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
        out.close();
        if (!out) throw InputError(path + ": cannot write the JSON summary");
    });
}

int runBatch(const BatchArgs& a) {
    BatchFile file = readBatchJobs(a.jobsFile);
    const size_t n = file.jobs.size();
    for (BatchJob& job : file.jobs) {
        job.render.threads = a.threads;
        job.render.quiet = a.quiet;
    }
    SceneCache cache(file, a.threads, a.quiet);
    std::vector<JobRecord> records(n);
    auto start = std::chrono::steady_clock::now();
    InterruptGuard guard;  // Ctrl-C between renders stops the batch too (a second one quits at once)
    interruptFlag().store(false);
    bool stopped = false;
    for (size_t i = 0; i < n && !stopped; ++i) {
        const BatchJob& job = file.jobs[i];
        JobRecord& rec = records[i];
        if (!a.quiet) {
            std::optional<double> eta = estimateRemaining(file, records, i);
            std::cerr << "tessera batch: job " << i + 1 << " of " << n << ", " << job.label() << ": " << job.render.scene << " ("
                      << formatDuration(secondsSince(start)) << " elapsed, batch eta " << (eta ? formatDuration(*eta) : "?")
                      << ")" << std::endl;
        }
        auto jobStart = std::chrono::steady_clock::now();
        try {
            runJob(job, n, cache, rec);
        } catch (const InputError& e) {
            rec.status = "failed";
            rec.error = e.what();
        } catch (const std::exception& e) {  // e.g. out of memory on a huge scene: that job fails, not the batch
            rec.status = "failed";
            rec.error = std::string("internal error: ") + e.what();
        }
        rec.seconds = secondsSince(jobStart);
        if (rec.status == "failed") printError(file.path + ": " + job.label() + ": " + rec.error);
        cache.release(job);
        stopped = interruptFlag().load() || rec.status == "interrupted" || (a.failFast && rec.status == "failed");
    }

    int counts[4] = {0, 0, 0, 0};  // ok, failed, interrupted, not run
    nlohmann::json jobs = nlohmann::json::array();
    for (size_t i = 0; i < n; ++i) {
        const std::string& st = records[i].status;
        ++counts[st == "ok" ? 0 : st == "failed" ? 1 : st == "interrupted" ? 2 : 3];
        jobs.push_back(jobJson(file.jobs[i], records[i]));
    }
    nlohmann::json summary = {{"jobs_file", file.path}, {"jobs", jobs},           {"ok", counts[0]},
                              {"failed", counts[1]},    {"interrupted", counts[2]}, {"not_run", counts[3]},
                              {"scene_loads", cache.loads()}, {"accel_builds", cache.builds()}, {"seconds", secondsSince(start)}};
    if (!a.quiet)
        std::cerr << "tessera batch: " << counts[0] << " of " << n << " jobs rendered, " << counts[1] << " failed"
                  << (counts[2] ? ", " + std::to_string(counts[2]) + " interrupted" : "")
                  << (counts[3] ? ", " + std::to_string(counts[3]) + " not run" : "") << "; " << cache.loads() << " scene load(s), "
                  << cache.builds() << " accel build(s), " << formatDuration(secondsSince(start)) << std::endl;
    if (!a.jsonSummary.empty()) writeSummaryFile(a.jsonSummary, summary);
    // Error texts may quote bytes from scene files: invalid UTF-8 is replaced, never thrown on.
    if (a.json) std::cout << summary.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << std::endl;
    if (interruptFlag().load() || counts[2] > 0) return 130;
    return counts[1] > 0 ? 1 : 0;
}

}  // namespace

Runner addBatchCommand(CLI::App& app) {
    auto a = std::make_shared<BatchArgs>();
    CLI::App* cmd = app.add_subcommand("batch", "Render the jobs of a JSON file, loading each scene and structure once");
    cmd->add_option("JOBS", a->jobsFile,
                    "jobs file: {\"defaults\": {...}, \"jobs\": [{\"scene\": ..., \"camera\": ..., \"spp\": ..., \"output\": ...}, ...]} "
                    "(format: writeup.md, \"Batch rendering\"); relative paths are relative to its folder")
        ->required();
    cmd->add_option("--threads", a->threads, "worker threads (default: all cores)")->check(CLI::Range(1, 4096));
    cmd->add_option("--json-summary", a->jsonSummary, "write the JSON summary (every job's status, outputs, time) to this file");
    cmd->add_flag("--json", a->json, "print the JSON summary on stdout");
    cmd->add_flag("--fail-fast", a->failFast, "stop at the first failed job (default: keep going)");
    cmd->add_flag("--quiet", a->quiet, "no progress output (failed jobs are still reported)");
    cmd->footer("A failed job is reported on stderr (file, job, reason) and the batch goes on. Exit code: 0 every job\n"
                "rendered, 1 some failed, 2 the jobs file is malformed (nothing rendered), 130 interrupted. Ctrl-C stops\n"
                "the current render, writes what it has and ends the batch with its summary.");
    return [a] { return runBatch(*a); };
}

}  // namespace tessera::app
