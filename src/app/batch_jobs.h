#pragma once
/// \file batch_jobs.h
/// The JOBS file of `tessera batch`: JSON, `{"defaults": {...}, "jobs": [{...}, ...]}`, each job a
/// render (scene, camera, integrator, accel, sampler, spp or time, resolution, seed, max-depth, output, png,
/// environment overrides, limits) whose keys override the defaults'. The format is documented in
/// writeup.md ("Batch rendering").
///
/// The file is checked whole before anything renders: its syntax, its structure, every key name,
/// every value's type and numeric range, that each job has a scene and that no two jobs write the
/// same image. Any problem is an InputError "FILE: /json/pointer: problem" (exit 2). Values whose
/// validity depends on the scene or on the renderer (integrator and accel names, the resolution
/// text, camera names and indices, environment files) are checked when their job runs and fail only
/// that job. This parser reads untrusted bytes: tests/fuzz/fuzz_batch_jobs.cpp.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "app/render_job.h"

namespace tessera::app {

/// How a job picks its camera. Look-at and fov overrides live in the job's SceneOptions.
struct CameraChoice {
    enum class Kind { Scene, Index, Name } kind = Kind::Scene;  ///< Scene: the file's first camera
    int index = -1;    ///< Kind::Index: the file's cameras[index]
    std::string name;  ///< Kind::Name: a camera's or a camera node's name
};

struct BatchJob {
    size_t index = 0;  ///< position in /jobs
    std::string name;  ///< the job's "name" (empty: none)
    RenderJob render;  ///< relative paths already resolved against the JOBS file's folder
    CameraChoice camera;
    /// "/jobs/3 (name)": how messages and the summary name the job.
    std::string label() const;
};

struct BatchFile {
    std::string path;
    std::vector<BatchJob> jobs;
};

/// The largest JOBS file read (a list of renders is kilobytes; this bounds a hostile one).
constexpr size_t kMaxBatchFileBytes = 16u << 20;

/// Parses the text of a JOBS file; `path` names it in messages and its folder anchors relative paths.
BatchFile parseBatchJobs(std::string_view text, const std::string& path);
/// Reads and parses `path` (InputError when it cannot be read or is over kMaxBatchFileBytes).
BatchFile readBatchJobs(const std::string& path);

}  // namespace tessera::app
