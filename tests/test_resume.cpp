// Checkpoint and resume through the CLI: a render stopped (in the middle of a pass, or twice) and
// resumed to the same spp gives the same bits in every float of the EXR and the same provenance
// as a render that was never stopped, for ptnee (film sums) and bdpt (splats merged in tile
// order); and a checkpoint that is corrupt, truncated or from other settings is refused.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstring>
#include <fstream>
#include <map>

#include "io/image_output.h"
#include "cli_run.h"
#include "test_helpers.h"

namespace {

namespace fs = std::filesystem;

using tessera::test::CliRun;

/// Runs `tessera render` on the Cornell box with `args`; stderr is captured.
CliRun render(const fs::path& dir, const std::string& args) {
    return tessera::test::runTessera(dir, "render '" + tessera::test::sourcePath("scenes/cornell-box/cornell-box.gltf") +
                                              "' --quiet --no-png " + args);
}

void expectSameImage(const fs::path& a, const fs::path& b) {
    auto [mx, my] = tessera::test::expectSameBitsAndProvenance(
        a, b, {"tessera:spp", "tessera:samples", "tessera:seed", "tessera:integrator", "tessera:resolution", "tessera:scene_hash",
               "tessera:max_depth", "tessera:nonfinite_dropped", "tessera:interrupted"});
    EXPECT_EQ(mx["tessera:interrupted"], "false");
    EXPECT_EQ(my["tessera:resumed"], "true");
}

/// Renders once straight through and once stopped after each of `stops` tiles (then resumed),
/// with different thread counts, and compares.
void expectResumeIsBitIdentical(const std::string& integrator, const std::vector<int>& stops) {
    std::string name = "resume-" + integrator;
    for (int s : stops) name += "-" + std::to_string(s);
    fs::path dir = tessera::test::tempDir(name);
    // 80x56 with 32-pixel tiles: 6 tiles per pass; passes of 1, 1, 2, 4, 2 spp.
    std::string common = "--integrator " + integrator + " --spp 10 --resolution 80x56 --seed 11 ";
    CliRun full = render(dir, common + "--threads 2 -o '" + (dir / "full.exr").string() + "'");
    ASSERT_EQ(full.code, 0) << full.err;
    std::string part = common + "-o '" + (dir / "part.exr").string() + "' ";
    fs::path ckpt = dir / "part.exr.ckpt";
    for (size_t k = 0; k < stops.size(); ++k) {
        std::string args = part + "--threads " + std::to_string(1 + k % 2) + " --stop-after-tiles " + std::to_string(stops[k]);
        CliRun stopped = render(dir, args + (k == 0 ? " --checkpoint 3600" : " --resume"));
        ASSERT_EQ(stopped.code, 130) << stopped.err;
        ASSERT_TRUE(fs::exists(ckpt));
        // The interrupted render still wrote a valid EXR that says so.
        auto md = tessera::test::imageMetadata(tessera::io::readImage((dir / "part.exr").string()));
        EXPECT_EQ(md["tessera:interrupted"], "true");
    }
    CliRun resumed = render(dir, part + "--threads 2 --resume");
    ASSERT_EQ(resumed.code, 0) << resumed.err;
    EXPECT_FALSE(fs::exists(ckpt)) << "a finished render leaves no checkpoint";
    expectSameImage(dir / "full.exr", dir / "part.exr");
    for (const auto& e : fs::directory_iterator(dir))
        EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}

}  // namespace

TEST(Resume, PtneeStoppedMidPassResumesBitIdentical) { expectResumeIsBitIdentical("ptnee", {9}); }

TEST(Resume, PtneeStoppedAtPassBoundaryResumesBitIdentical) { expectResumeIsBitIdentical("ptnee", {12}); }

TEST(Resume, BdptStoppedTwiceResumesBitIdentical) { expectResumeIsBitIdentical("bdpt", {4, 9}); }

TEST(Resume, CorruptTruncatedOrMismatchedCheckpointIsRefused) {
    fs::path dir = tessera::test::tempDir("resume-refused");
    std::string args = "--spp 6 --resolution 48x40 -o '" + (dir / "x.exr").string() + "' ";
    CliRun stopped = render(dir, args + "--seed 2 --checkpoint 0 --stop-after-tiles 3");
    ASSERT_EQ(stopped.code, 130) << stopped.err;
    fs::path ckpt = dir / "x.exr.ckpt";
    std::ifstream in(ckpt, std::ios::binary);
    std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(good.size(), 1000u);
    auto expectRefused = [&](const std::string& bytes, const std::string& extra, const std::string& reason) {
        std::ofstream(ckpt, std::ios::binary | std::ios::trunc) << bytes;
        CliRun r = render(dir, args + (extra.find("--seed") == std::string::npos ? "--seed 2 " : "") + extra + " --resume");
        EXPECT_EQ(r.code, 2) << reason << ": " << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_EQ(r.err.rfind("tessera: error: " + ckpt.string() + ": ", 0), 0u) << r.err;
        EXPECT_NE(r.err.find(reason), std::string::npos) << r.err;
    };
    std::string flipped = good;
    flipped[flipped.size() / 2] ^= 0x10;
    expectRefused(flipped, "", "CRC-32 mismatch");
    expectRefused(good.substr(0, good.size() / 3), "", "truncated");
    expectRefused(good.substr(0, 6), "", "truncated");
    expectRefused(good + "extra", "", "trailing bytes");
    expectRefused("not a checkpoint at all", "", "not a Tessera checkpoint");
    expectRefused(good, "--integrator pt", "integrator is 'ptnee' in the checkpoint, 'pt' now");
    expectRefused(good, "--seed 3", "seed is '2' in the checkpoint, '3' now");
    expectRefused(good, "--fov 30", "camera is");
    fs::remove(ckpt);
    CliRun missing = render(dir, args + "--seed 2 --resume");
    EXPECT_EQ(missing.code, 2);
    EXPECT_NE(missing.err.find("no checkpoint to resume"), std::string::npos) << missing.err;
    // A spp change is a different render: refused too, while the right one still resumes.
    std::ofstream(ckpt, std::ios::binary | std::ios::trunc) << good;
    CliRun other = render(dir, "--spp 7 --resolution 48x40 --seed 2 -o '" + (dir / "x.exr").string() + "' --resume");
    EXPECT_EQ(other.code, 2);
    EXPECT_NE(other.err.find("spp_target is '6' in the checkpoint, '7' now"), std::string::npos) << other.err;
    CliRun ok = render(dir, args + "--seed 2 --resume");
    EXPECT_EQ(ok.code, 0) << ok.err;
}
