// `tessera farm` without a cluster: the scripts it writes, run by hand as Slurm would run them
// (one shell per array task, then the merge), give the bits of one render; the merge is submitted
// with --dependency=afterok on the array; a re-run submits only the ranges without a partial.
// tests/test_farm_slurm.sh runs the same on a real local Slurm (ctest -L slurm).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstring>
#include <fstream>

#include "io/image_output.h"
#include "test_helpers.h"

namespace {

namespace fs = std::filesystem;

int run(const std::string& cmd, std::string* out = nullptr) {
    std::string full = "timeout 120 " + cmd + " > /tmp/tessera-farm-test.$$ 2>&1; rc=$?; cat /tmp/tessera-farm-test.$$; rm -f /tmp/tessera-farm-test.$$; exit $rc";
    FILE* p = popen(full.c_str(), "r");
    std::string text;
    char buf[4096];
    while (p && std::fgets(buf, sizeof buf, p)) text += buf;
    int status = p ? pclose(p) : -1;
    if (out) *out = text;
    EXPECT_TRUE(WIFEXITED(status)) << cmd;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string slurp(const fs::path& p) {
    std::ifstream in(p);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(Farm, ScriptsRenderTheSameBitsAndRerunsSubmitOnlyMissingRanges) {
    fs::path dir = tessera::test::tempDir("farm-scripts");
    fs::path out = dir / "run", log = dir / "sbatch.log", sbatch = dir / "sbatch";
    // A stand-in for sbatch: logs its arguments, prints a job id (--parsable).
    {
        std::ofstream s(sbatch);
        s << "#!/bin/bash\necho \"$*\" >> '" << log.string() << "'\nn=$(wc -l < '" << log.string() << "')\necho $((100 + n))\n";
    }
    fs::permissions(sbatch, fs::perms::owner_all);
    const std::string scene = tessera::test::sourcePath("scenes/cornell-box/cornell-box.gltf");
    const std::string renderOpts = " --resolution 40x30 --seed 5 --integrator bdpt --max-depth 4";
    const std::string farmBase = std::string(TESSERA_BINARY) + " farm '" + scene + "' --parts 4 --spp 10 --out '" + out.string() +
                                 "' --sbatch '" + sbatch.string() + "' --cpus-per-task 1 --json";
    const std::string farm = farmBase + " -- " + renderOpts;
    std::string text;
    ASSERT_EQ(run(farm, &text), 0) << text;
    EXPECT_NE(text.find("\"array_job\":\"101\""), std::string::npos) << text;
    EXPECT_NE(text.find("\"merge_job\":\"102\""), std::string::npos) << text;
    std::string submitted = slurp(log);
    EXPECT_NE(submitted.find("--parsable " + (out / "render.sbatch").string()), std::string::npos) << submitted;
    EXPECT_NE(submitted.find("--dependency=afterok:101 --kill-on-invalid-dep=yes " + (out / "merge.sbatch").string()), std::string::npos) << submitted;
    std::string render = slurp(out / "render.sbatch");
    EXPECT_NE(render.find("#SBATCH --array=0,1,2,3\n"), std::string::npos) << render;
    EXPECT_NE(render.find("RANGES=( 0:2 2:5 5:7 7:10 )"), std::string::npos) << render;

    // Slurm runs task 1 (samples 2:5): a re-run submits only the three others.
    ASSERT_EQ(run("env SLURM_ARRAY_TASK_ID=1 bash '" + (out / "render.sbatch").string() + "'", &text), 0) << text;
    ASSERT_TRUE(fs::exists(out / "part_2-5.partial"));
    ASSERT_EQ(run(farmBase + " --dry-run -- " + renderOpts, &text), 0) << text;
    EXPECT_NE(text.find("#SBATCH --array=0,2,3\n"), std::string::npos) << text;
    ASSERT_EQ(run(farm, &text), 0) << text;
    EXPECT_NE(slurp(out / "render.sbatch").find("#SBATCH --array=0,2,3\n"), std::string::npos);

    // The other tasks, then the merge: the image of one 10-spp render.
    for (int k : {0, 2, 3})
        ASSERT_EQ(run("env SLURM_ARRAY_TASK_ID=" + std::to_string(k) + " bash '" + (out / "render.sbatch").string() + "'", &text), 0)
            << text;
    // Everything rendered: only the merge is submitted, with no dependency.
    fs::remove(log);
    ASSERT_EQ(run(farm, &text), 0) << text;
    EXPECT_NE(text.find("\"array_job\":\"\""), std::string::npos) << text;
    EXPECT_EQ(slurp(log).find("dependency"), std::string::npos);
    ASSERT_EQ(run("bash '" + (out / "merge.sbatch").string() + "'", &text), 0) << text;

    fs::path full = dir / "full.exr";
    ASSERT_EQ(run(std::string(TESSERA_BINARY) + " render '" + scene + "' --quiet --no-png --spp 10 " + renderOpts + " -o '" +
                      full.string() + "'", &text), 0) << text;
    tessera::io::Image a = tessera::io::readImage((out / "cornell-box.exr").string()), b = tessera::io::readImage(full.string());
    ASSERT_EQ(a.rgba.size(), b.rgba.size());
    EXPECT_EQ(std::memcmp(a.rgba.data(), b.rgba.data(), a.rgba.size() * sizeof(float)), 0);
    EXPECT_TRUE(fs::exists(out / "cornell-box.png"));
    EXPECT_TRUE(fs::exists(out / "cornell-box_stderr.exr"));
}

TEST(Farm, RefusesOptionsItOwns) {
    fs::path dir = tessera::test::tempDir("farm-options");
    const std::string scene = tessera::test::sourcePath("scenes/cornell-box/cornell-box.gltf");
    std::string text;
    EXPECT_EQ(run(std::string(TESSERA_BINARY) + " farm '" + scene + "' --parts 4 --spp 8 --out '" + dir.string() +
                  "' --dry-run -- --samples 0:4", &text), 2) << text;
    EXPECT_NE(text.find("--samples is the farm's to set"), std::string::npos) << text;
    EXPECT_EQ(run(std::string(TESSERA_BINARY) + " farm '" + scene + "' --parts 9 --spp 8 --out '" + dir.string() + "' --dry-run", &text), 2)
        << text;
    EXPECT_NE(text.find("--parts 9"), std::string::npos) << text;
}

}  // namespace
