// A render that fails never clobbers an existing output and leaves no temporary file behind:
// invalid scene, bad display transform, a destination that cannot be replaced, and a render
// killed by a second Ctrl-C while it works.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <thread>

#include "io/image_output.h"
#include "test_helpers.h"

namespace {

namespace fs = std::filesystem;

std::string readAll(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

int exitCodeOf(const std::string& cmd) {
    int status = std::system(cmd.c_str());
    EXPECT_TRUE(WIFEXITED(status)) << cmd << ": terminated by a signal";
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

void expectNoTemporaryFiles(const fs::path& dir) {
    for (const auto& e : fs::recursive_directory_iterator(dir))
        EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << "left behind: " << e.path();
}

const std::string kBox = tessera::test::sourcePath("scenes/cornell-box/cornell-box.gltf");

}  // namespace

TEST(RobustOutputs, FailedRenderNeverClobbersExistingFiles) {
    fs::path dir = tessera::test::tempDir("no-clobber");
    const std::string sentinel = "previous render, must survive";
    for (const char* name : {"out.exr", "out.png"}) std::ofstream(dir / name) << sentinel;
    const std::string out = " -o '" + (dir / "out.exr").string() + "' --png '" + (dir / "out.png").string() + "'";
    const std::string bin = std::string(TESSERA_BINARY) + " render ";

    // An invalid scene, an unknown OCIO view, an unknown integrator: refused before anything is written.
    EXPECT_EQ(exitCodeOf(bin + "'" + tessera::test::sourcePath("tests/corpus/malformed/truncated-json.gltf") + "' --quiet" + out +
                         " 2>/dev/null"),
              2);
    EXPECT_EQ(exitCodeOf(bin + "'" + kBox + "' --quiet --spp 1 --resolution 16x16 --view NoSuchView" + out + " 2>/dev/null"), 2);
    EXPECT_EQ(exitCodeOf(bin + "'" + kBox + "' --quiet --spp 1 --resolution 16x16 --integrator nope" + out + " 2>/dev/null"), 2);
    for (const char* name : {"out.exr", "out.png"}) EXPECT_EQ(readAll(dir / name), sentinel) << name;

    // A destination that cannot be replaced (a non-empty directory): the write fails after the
    // render, the directory and its content stay, and the temporary file is removed.
    fs::create_directories(dir / "taken.exr");
    std::ofstream(dir / "taken.exr" / "keep.txt") << sentinel;
    EXPECT_EQ(exitCodeOf(bin + "'" + kBox + "' --quiet --spp 1 --resolution 16x16 --no-png -o '" + (dir / "taken.exr").string() +
                         "' 2>/dev/null"),
              2);
    EXPECT_EQ(readAll(dir / "taken.exr" / "keep.txt"), sentinel);
    expectNoTemporaryFiles(dir);
}

TEST(RobustOutputs, SecondInterruptLeavesOldOrCompleteFilesOnly) {
    fs::path dir = tessera::test::tempDir("double-interrupt");
    const std::string sentinel = "previous render, must survive";
    std::ofstream(dir / "out.exr") << sentinel;
    // Several runs, signalled at different moments: each must leave either the old file or a
    // complete EXR, and a checkpoint that is either absent or complete, never a temporary file.
    for (int delayMs : {0, 7, 40}) {
        fs::remove(dir / "out.exr.ckpt");
        pid_t pid = fork();
        ASSERT_GE(pid, 0);
        if (pid == 0) {
            if (!freopen("/dev/null", "w", stderr)) _exit(126);
            execl(TESSERA_BINARY, TESSERA_BINARY, "render", kBox.c_str(), "--quiet", "--no-png", "--spp", "100000",
                  "--resolution", "64x64", "--threads", "1", "--checkpoint", "0", "-o", (dir / "out.exr").c_str(), nullptr);
            _exit(127);
        }
        // The first checkpoint (after the first pass) says the render is under way, signal handlers
        // installed; then signal at different moments of the passes and checkpoint writes.
        for (int i = 0; i < 3000 && !fs::exists(dir / "out.exr.ckpt"); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
        ASSERT_TRUE(fs::exists(dir / "out.exr.ckpt"));
        std::this_thread::sleep_for(std::chrono::milliseconds(delayMs));
        kill(pid, SIGINT);
        kill(pid, SIGINT);
        int status = 0;
        waitpid(pid, &status, 0);
        ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
        EXPECT_EQ(WEXITSTATUS(status), 130);
        std::string now = readAll(dir / "out.exr");
        if (now != sentinel) {
            EXPECT_NO_THROW(tessera::io::readImage((dir / "out.exr").string()));
        }
        if (fs::exists(dir / "out.exr.ckpt")) {
            // Complete, or --resume would say so: check through the CLI that it is accepted.
            std::string cmd = std::string(TESSERA_BINARY) + " render '" + kBox + "' --quiet --no-png --spp 100000 --resolution 64x64 "
                              "--stop-after-tiles 1 --resume -o '" + (dir / "out.exr").string() + "' 2>/dev/null";
            EXPECT_EQ(exitCodeOf(cmd), 130) << "the checkpoint left behind does not resume";
        }
        expectNoTemporaryFiles(dir);
    }
}
