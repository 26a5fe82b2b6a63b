// `tessera batch JOBS.json`: failed jobs are reported and the batch goes on; the good images are
// bit-identical to `tessera render` with the same options; a scene is loaded once and its
// structure built once per kind; cameras by name, index and look-at; a malformed jobs file is
// refused with one line naming the JSON pointer; Ctrl-C stops the batch with what it has.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "app/batch_jobs.h"
#include "core/error.h"
#include "io/image_output.h"
#include "cli_run.h"
#include "test_helpers.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kBox = tessera::test::sourcePath("scenes/cornell-box/cornell-box.gltf");

std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::stringstream ss(text);
    for (std::string line; std::getline(ss, line);) out.push_back(line);
    return out;
}

using tessera::test::CliRun;

CliRun runTessera(const std::string& args, const fs::path& dir) { return tessera::test::runTessera(dir, args); }

fs::path writeJobs(const fs::path& dir, const json& jobs, const std::string& name = "jobs.json") {
    std::ofstream(dir / name) << jobs.dump(2);
    return dir / name;
}

/// Runs a batch with --json and returns the parsed summary.
json batch(const fs::path& jobsFile, const fs::path& dir, int expectedCode, CliRun* run = nullptr) {
    CliRun r = runTessera("batch '" + jobsFile.string() + "' --quiet --json", dir);
    EXPECT_EQ(r.code, expectedCode) << r.err;
    if (run) *run = r;
    json summary = json::parse(r.out, nullptr, false);
    EXPECT_FALSE(summary.is_discarded()) << "stdout is not one JSON summary: " << r.out;
    return summary;
}

/// The same bits, pixel for pixel.
void expectSameImage(const fs::path& a, const fs::path& b) {
    ASSERT_TRUE(fs::exists(a)) << a;
    ASSERT_TRUE(fs::exists(b)) << b;
    tessera::io::Image x = tessera::io::readImage(a.string()), y = tessera::io::readImage(b.string());
    ASSERT_EQ(x.width, y.width);
    ASSERT_EQ(x.height, y.height);
    EXPECT_TRUE(x.rgba == y.rgba) << a << " and " << b << " differ";
}

bool sameImage(const fs::path& a, const fs::path& b) {
    return tessera::io::readImage(a.string()).rgba == tessera::io::readImage(b.string()).rgba;
}

}  // namespace

TEST(Batch, BadJobAndMissingSceneAreReportedAndTheGoodImagesMatchRender) {
    fs::path dir = tessera::test::tempDir("batch-mixed");
    json jobs = {
        {"defaults", {{"scene", kBox}, {"resolution", "32x24"}, {"spp", 2}, {"png", false}}},
        {"jobs",
         {{{"name", "good-pt"}, {"integrator", "pt"}, {"sampler", "sobol"}, {"seed", 3}, {"output", "good-pt.exr"}, {"png", true}},
          {{"name", "bad-integrator"}, {"integrator", "nonsense"}, {"output", "bad.exr"}},
          {{"name", "no-scene"}, {"scene", "missing/nowhere.gltf"}, {"output", "missing.exr"}},
          {{"name", "good-lookat"},
           {"integrator", "ptnee"},
           {"sampler", "independent"},
           {"max-depth", 3},
           {"camera", {{"look-at", {{0.278, 0.273, -0.6}, {0.25, 0.3, 0.0}, {0, 1, 0}}}, {"fov", 45}}},
           {"output", "out/good-lookat.exr"}},
          {{"name", "good-vcm"}, {"integrator", "vcm"}, {"radius", 0.05}, {"alpha", 0.6}, {"photons", 500}, {"output", "good-vcm.exr"}}}},
    };
    CliRun run;
    json summary = batch(writeJobs(dir, jobs), dir, 1, &run);
    ASSERT_EQ(summary["jobs"].size(), 5u);
    EXPECT_EQ(summary["ok"], 3);
    EXPECT_EQ(summary["failed"], 2);
    const json& j = summary["jobs"];
    EXPECT_EQ(j[0]["status"], "ok");
    EXPECT_EQ(j[1]["status"], "failed");
    EXPECT_EQ(j[2]["status"], "failed");
    EXPECT_EQ(j[3]["status"], "ok");
    EXPECT_NE(j[1]["error"].get<std::string>().find("nonsense"), std::string::npos) << j[1];
    EXPECT_NE(j[2]["error"].get<std::string>().find("nowhere.gltf: no such file"), std::string::npos) << j[2];
    EXPECT_EQ(j[0]["outputs"]["exr"], (dir / "good-pt.exr").string());
    EXPECT_EQ(j[0]["outputs"]["png"], (dir / "good-pt.png").string());
    EXPECT_FALSE(j[3]["outputs"].contains("png"));
    // Each failure is one line on stderr naming the jobs file, the job and the reason.
    std::vector<std::string> errors = lines(run.err);
    ASSERT_EQ(errors.size(), 2u) << run.err;
    EXPECT_EQ(errors[0].rfind("tessera: error: " + (dir / "jobs.json").string() + ": /jobs/1 (bad-integrator): unknown integrator", 0), 0u)
        << errors[0];
    EXPECT_EQ(errors[1].rfind("tessera: error: " + (dir / "jobs.json").string() + ": /jobs/2 (no-scene): ", 0), 0u) << errors[1];
    EXPECT_FALSE(fs::exists(dir / "bad.exr"));
    EXPECT_FALSE(fs::exists(dir / "missing.exr"));

    // The good jobs are exactly what `tessera render` makes of the same options.
    const std::string common = " --quiet --resolution 32x24 --spp 2";
    ASSERT_EQ(runTessera("render '" + kBox + "'" + common + " --integrator pt --sampler sobol --seed 3 -o '" + (dir / "ref-pt.exr").string() +
                          "' --png '" + (dir / "ref-pt.png").string() + "'",
                      dir)
                  .code,
              0);
    expectSameImage(dir / "good-pt.exr", dir / "ref-pt.exr");
    expectSameImage(dir / "good-pt.png", dir / "ref-pt.png");
    ASSERT_EQ(runTessera("render '" + kBox + "'" + common +
                          " --no-png --integrator ptnee --sampler independent --max-depth 3 --look-at 0.278,0.273,-0.6,0.25,0.3,0,0,1,0 --fov 45 -o '" +
                          (dir / "ref-lookat.exr").string() + "'",
                      dir)
                  .code,
              0);
    expectSameImage(dir / "out/good-lookat.exr", dir / "ref-lookat.exr");
    // Photon settings reach the integrator as render's --radius, --alpha and --photons.
    ASSERT_EQ(runTessera("render '" + kBox + "'" + common + " --no-png --integrator vcm --radius 0.05 --alpha 0.6 --photons 500 -o '" +
                          (dir / "ref-vcm.exr").string() + "'",
                      dir)
                  .code,
              0);
    expectSameImage(dir / "good-vcm.exr", dir / "ref-vcm.exr");
}

TEST(Batch, SceneLoadedOnceAndStructureBuiltOncePerKind) {
    fs::path dir = tessera::test::tempDir("batch-cache");
    json jobs = {
        {"defaults", {{"scene", kBox}, {"resolution", "16x16"}, {"spp", 1}, {"png", false}}},
        {"jobs",
         {{{"output", "a.exr"}},
          {{"output", "b.exr"}, {"seed", 7}, {"integrator", "lt"}},
          {{"output", "c.exr"}, {"accel", "bvh"}},
          {{"output", "d.exr"}, {"env", {0.25, 0.5, 1.0}}},  // another environment: another scene
          {{"output", "e.exr"}, {"accel", "bvh"}, {"spp", 2}}}},
    };
    json summary = batch(writeJobs(dir, jobs), dir, 0);
    EXPECT_EQ(summary["ok"], 5);
    EXPECT_EQ(summary["scene_loads"], 2);
    EXPECT_EQ(summary["accel_builds"], 3);  // embree and bvh over the box, embree over the box with --env
    const json& j = summary["jobs"];
    std::vector<bool> loaded, built;
    for (const json& x : j) {
        loaded.push_back(x["scene_loaded"]);
        built.push_back(x["accel_built"]);
    }
    EXPECT_EQ(loaded, (std::vector<bool>{true, false, false, true, false}));
    EXPECT_EQ(built, (std::vector<bool>{true, false, true, true, false}));
    EXPECT_EQ(j[2]["accel"], "bvh");

    // The environment override is the render's --env, and a structure shared by jobs does not change their bits.
    ASSERT_EQ(runTessera("render '" + kBox + "' --quiet --resolution 16x16 --spp 1 --no-png --env 0.25,0.5,1 -o '" +
                          (dir / "ref-env.exr").string() + "'",
                      dir)
                  .code,
              0);
    expectSameImage(dir / "d.exr", dir / "ref-env.exr");
    ASSERT_EQ(runTessera("render '" + kBox + "' --quiet --resolution 16x16 --spp 2 --no-png --accel bvh -o '" +
                          (dir / "ref-e.exr").string() + "'",
                      dir)
                  .code,
              0);
    expectSameImage(dir / "e.exr", dir / "ref-e.exr");

    // Without --quiet each load and build is one log line.
    CliRun r = runTessera("batch '" + (dir / "jobs.json").string() + "'", dir);
    EXPECT_EQ(r.code, 0) << r.err;
    size_t loads = 0, builds = 0;
    for (const std::string& line : lines(r.err)) {
        loads += line.rfind("tessera batch: loaded ", 0) == 0;
        builds += line.rfind("tessera batch: built ", 0) == 0;
    }
    EXPECT_EQ(loads, 2u) << r.err;
    EXPECT_EQ(builds, 3u) << r.err;
    EXPECT_NE(r.err.find("tessera batch: job 5 of 5"), std::string::npos) << r.err;
}

TEST(Batch, CameraByNameIndexNodeNameAndLookAt) {
    fs::path dir = tessera::test::tempDir("batch-cameras");
    // The box with two more cameras: "side" (cameras[1], node "sideNode") and an orthographic one
    // (cameras[2]), which the scene still loads with since its first camera renders.
    json gltf = json::parse(tessera::test::readWholeFile(kBox));
    fs::copy_file(fs::path(kBox).replace_extension(".bin"), dir / "cornell-box.bin");
    gltf["cameras"].push_back({{"name", "side"}, {"type", "perspective"}, {"perspective", {{"yfov", 0.9}, {"znear", 0.01}}}});
    gltf["cameras"].push_back({{"name", "ortho"}, {"type", "orthographic"},
                               {"orthographic", {{"xmag", 1.0}, {"ymag", 1.0}, {"znear", 0.01}, {"zfar", 10.0}}}});
    // Rotated 30° about +Y (quaternion x, y, z, w), looking into the box from the front left.
    gltf["nodes"].push_back({{"name", "sideNode"}, {"camera", 1}, {"translation", {0.1, 0.3, -0.5}},
                             {"rotation", {0.0, 0.9659258, 0.0, 0.2588190}}});
    gltf["nodes"].push_back({{"name", "orthoNode"}, {"camera", 2}});
    int n = int(gltf["nodes"].size());
    gltf["scenes"][0]["nodes"].push_back(n - 2);
    gltf["scenes"][0]["nodes"].push_back(n - 1);
    std::ofstream(dir / "box.gltf") << gltf.dump();

    json jobs = {
        {"defaults", {{"scene", "box.gltf"}, {"resolution", "24x24"}, {"spp", 1}, {"png", false}}},
        {"jobs",
         {{{"name", "default"}},
          {{"name", "by-name"}, {"camera", "side"}},
          {{"name", "by-index"}, {"camera", 1}},
          {{"name", "by-node"}, {"camera", {{"name", "sideNode"}}}},
          {{"name", "by-index-fov"}, {"camera", {{"index", 1}, {"fov", 30}}}},
          {{"name", "lookat"}, {"camera", {{"look-at", {{0.1, 0.3, -0.5}, {0.3, 0.25, 0.2}}}}}},
          {{"name", "unknown"}, {"camera", "nope"}},
          {{"name", "ortho"}, {"camera", "ortho"}}}},
    };
    json summary = batch(writeJobs(dir, jobs), dir, 1);
    const json& j = summary["jobs"];
    for (int i = 0; i < 6; ++i) EXPECT_EQ(j[i]["status"], "ok") << j[i];
    EXPECT_EQ(summary["scene_loads"], 1);
    EXPECT_NE(j[6]["error"].get<std::string>().find("no camera named 'nope' (the file places 0 'camera' (node 'camera'), 1 'side' (node 'sideNode'), 2 'ortho'"),
              std::string::npos)
        << j[6];
    EXPECT_NE(j[7]["error"].get<std::string>().find("cameras[2]: only perspective cameras are supported"), std::string::npos) << j[7];

    expectSameImage(dir / "out/by-name.exr", dir / "out/by-index.exr");
    expectSameImage(dir / "out/by-name.exr", dir / "out/by-node.exr");
    EXPECT_FALSE(sameImage(dir / "out/by-name.exr", dir / "out/default.exr"));
    EXPECT_FALSE(sameImage(dir / "out/by-name.exr", dir / "out/by-index-fov.exr"));
    // The default camera is the render's; look-at (with the scene camera's fov) is the render's --look-at.
    const std::string common = " --quiet --resolution 24x24 --spp 1 --no-png";
    ASSERT_EQ(runTessera("render box.gltf" + common + " -o ref-default.exr", dir).code, 0);
    expectSameImage(dir / "out/default.exr", dir / "ref-default.exr");
    ASSERT_EQ(runTessera("render box.gltf" + common + " --look-at 0.1,0.3,-0.5,0.3,0.25,0.2 -o ref-lookat.exr", dir).code, 0);
    expectSameImage(dir / "out/lookat.exr", dir / "ref-lookat.exr");
}

TEST(Batch, MalformedJobsFileIsOneLineNamingThePointer) {
    fs::path dir = tessera::test::tempDir("batch-malformed");
    const std::string s = "\"scene\": \"" + kBox + "\"";
    struct Case {
        std::string text, expected;
    };
    const std::vector<Case> cases = {
        {"{\"jobs\": [", "line 1, column 11: not valid JSON"},
        {"{\"jobs\": [{" + s + "}]}\n}", "line 2, column 1: not valid JSON"},
        {"[]", "must be a JSON object"},
        {"{\"defaults\": {}}", "has no \"jobs\" array"},
        {"{\"jobs\": []}", "/jobs: is empty"},
        {"{\"jobs\": {}}", "/jobs: must be an array"},
        {"{\"job\": []}", "/job: unknown key"},
        {"{\"jobs\": [3]}", "/jobs/0: must be an object"},
        {"{\"jobs\": [{" + s + "}, {" + s + ", \"spp\": -2}]}", "/jobs/1/spp: must be an integer in [1, 1073741824], got -2"},
        {"{\"jobs\": [{" + s + ", \"spp\": 2.5}]}", "/jobs/0/spp: must be an integer"},
        {"{\"jobs\": [{" + s + ", \"sp\": 2}]}", "/jobs/0/sp: unknown key"},
        {"{\"jobs\": [{" + s + ", \"a/b~\": 2}]}", "/jobs/0/a~1b~0: unknown key"},
        {"{\"defaults\": {\"spp\": \"many\"}, \"jobs\": [{" + s + "}]}", "/defaults/spp: must be an integer"},
        {"{\"defaults\": {\"output\": \"x.exr\"}, \"jobs\": [{" + s + "}]}", "/defaults/output: an output belongs to one job"},
        {"{\"jobs\": [{" + s + ", \"spp\": 2, \"time\": 1}]}", "/jobs/0: give \"spp\" or \"time\", not both"},
        {"{\"jobs\": [{\"spp\": 2}]}", "/jobs/0: has no \"scene\""},
        {"{\"jobs\": [{" + s + ", \"time\": 0}]}", "/jobs/0/time: must be a number > 0"},
        {"{\"jobs\": [{" + s + ", \"seed\": 18446744073709551615}]}", "/jobs/0/seed: must be an integer"},
        {"{\"jobs\": [{" + s + ", \"max-depth\": -2}]}", "/jobs/0/max-depth: must be an integer in [-1,"},
        {"{\"jobs\": [{" + s + ", \"alpha\": 1.5}]}", "/jobs/0/alpha: must be a number"},
        {"{\"jobs\": [{" + s + ", \"photons\": 0}]}", "/jobs/0/photons: must be an integer in [1,"},
        {"{\"jobs\": [{" + s + ", \"spp\": 0}]}", "/jobs/0/spp: must be an integer in [1, 1073741824], got 0"},
        {"{\"jobs\": [{" + s + ", \"camera\": {\"look-at\": [[0,0,0], [1,\"a\",0]]}}]}", "/jobs/0/camera/look-at/1/1: must be a number"},
        {"{\"jobs\": [{" + s + ", \"camera\": {\"name\": \"a\", \"index\": 1}}]}", "/jobs/0/camera: give one of"},
        {"{\"jobs\": [{" + s + ", \"camera\": {\"fov\": 200}}]}", "/jobs/0/camera/fov: must be a number"},
        {"{\"jobs\": [{" + s + ", \"camera\": true}]}", "/jobs/0/camera: must be a camera index, a camera name or"},
        {"{\"jobs\": [{" + s + ", \"env\": [1, -1, 0]}]}", "/jobs/0/env/1: must be a number >= 0"},
        {"{\"jobs\": [{" + s + ", \"env-intensity\": 1e999}]}", "not valid JSON (number overflow parsing '1e999')"},
        {"{\"jobs\": [{" + s + ", \"name\": \"x\"}, {" + s + ", \"name\": \"x\", \"output\": \"y.exr\"}]}",
         "/jobs/1/name: \"x\" names /jobs/0 too"},
        {"{\"jobs\": [{" + s + ", \"output\": \"o.exr\"}, {" + s + ", \"output\": \"./o.exr\"}]}",
         "/jobs/1/output: writes " + (dir / "o.exr").string() + " like /jobs/0 does"},
        {"{\"jobs\": [{" + s + ", \"integrator\": \"\"}]}", "/jobs/0/integrator: must not be empty"},
        {"{\"jobs\": [{" + s + ", \"sampler\": \"halton\"}]}", "/jobs/0/sampler: unknown sampler \"halton\""},
        {"{\"jobs\": [{" + s + ", \"name\": \"\\u00e9\\ud800\"}]}", "not valid JSON"},
    };
    const std::string path = (dir / "jobs.json").string();
    for (const Case& c : cases) {
        try {
            tessera::app::parseBatchJobs(c.text, path);
            ADD_FAILURE() << "accepted: " << c.text;
        } catch (const tessera::InputError& e) {
            std::string what = e.what();
            EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
            EXPECT_NE(what.find(c.expected), std::string::npos) << c.text << "\n  got: " << what << "\n  want: " << c.expected;
            EXPECT_EQ(what.find('\n'), std::string::npos) << what;
        }
    }
    // The command line: exit 2, that one line on stderr, nothing on stdout, nothing rendered.
    for (size_t i : {size_t(0), size_t(8), size_t(19)}) {
        std::ofstream(dir / "jobs.json", std::ios::trunc) << cases[i].text;
        CliRun r = runTessera("batch jobs.json --json", dir);
        EXPECT_EQ(r.code, 2) << cases[i].text << "\n" << r.err;
        std::vector<std::string> errs = lines(r.err);
        ASSERT_EQ(errs.size(), 1u) << cases[i].text << "\n" << r.err;
        EXPECT_EQ(errs[0].rfind("tessera: error: jobs.json: ", 0), 0u) << errs[0];
        EXPECT_NE(errs[0].find(cases[i].expected), std::string::npos) << errs[0];
        EXPECT_TRUE(r.out.empty()) << r.out;
    }
    EXPECT_FALSE(fs::exists(dir / "out"));
    CliRun r = runTessera("batch no-such-jobs.json", dir);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "tessera: error: no-such-jobs.json: no such file\n");
}

TEST(Batch, InterruptStopsTheBatchWithWhatItHas) {
    fs::path dir = tessera::test::tempDir("batch-interrupt");
    json jobs = {
        {"defaults", {{"scene", kBox}, {"resolution", "32x32"}, {"png", false}}},
        {"jobs", {{{"output", "long.exr"}, {"time", 60}}, {{"output", "next.exr"}, {"spp", 1}}}},
    };
    writeJobs(dir, jobs);
    const std::string err = (dir / "stderr.txt").string(), jobsFile = (dir / "jobs.json").string(),
                      summaryFile = (dir / "summary.json").string();
    pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        if (!freopen(err.c_str(), "w", stderr)) _exit(126);
        execl(TESSERA_BINARY, TESSERA_BINARY, "batch", jobsFile.c_str(), "--threads", "1", "--json-summary", summaryFile.c_str(),
              nullptr);
        _exit(127);
    }
    // Signal once the first render reports progress (its scene is loaded and its structure built).
    auto start = std::chrono::steady_clock::now();
    while (tessera::test::readWholeFile(err).find("job 1/2") == std::string::npos && std::chrono::steady_clock::now() - start < std::chrono::seconds(30))
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    kill(pid, SIGINT);
    int status = 0;
    ASSERT_EQ(waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFEXITED(status)) << tessera::test::readWholeFile(err);
    EXPECT_EQ(WEXITSTATUS(status), 130) << tessera::test::readWholeFile(err);
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(40));
    json summary = json::parse(tessera::test::readWholeFile(summaryFile));
    EXPECT_EQ(summary["jobs"][0]["status"], "interrupted");
    EXPECT_EQ(summary["jobs"][1]["status"], "not run");
    EXPECT_EQ(summary["interrupted"], 1);
    EXPECT_EQ(summary["not_run"], 1);
    ASSERT_TRUE(fs::exists(dir / "long.exr"));
    bool markedInterrupted = false;
    for (const auto& [k, v] : tessera::io::readImage((dir / "long.exr").string()).metadata)
        markedInterrupted |= k == "tessera:interrupted" && v == "true";
    EXPECT_TRUE(markedInterrupted);
    EXPECT_FALSE(fs::exists(dir / "next.exr"));
}
