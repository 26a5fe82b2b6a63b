// Every file of tests/corpus/malformed makes `tessera render` fail cleanly: exit code 2, one line
// "tessera: error: FILE: ..." on stderr, no signal, no output file.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <fstream>

#include "test_helpers.h"

TEST(MalformedCorpus, EveryFileFailsWithOneLineAndExitTwo) {
    namespace fs = std::filesystem;
    fs::path corpus = tessera::test::sourcePath("tests/corpus/malformed");
    fs::path out = tessera::test::tempDir("malformed-corpus");
    int files = 0;
    for (const auto& entry : fs::directory_iterator(corpus)) {
        std::string ext = entry.path().extension().string();
        if (ext != ".gltf" && ext != ".glb") continue;
        ++files;
        std::string name = entry.path().filename().string();
        fs::path exr = out / (name + ".exr"), err = out / (name + ".err");
        std::string cmd = "timeout 60 " + std::string(TESSERA_BINARY) + " render '" + entry.path().string() +
                          "' --quiet --spp 1 -o '" + exr.string() + "' 2> '" + err.string() + "' > /dev/null";
        int status = std::system(cmd.c_str());
        ASSERT_TRUE(WIFEXITED(status)) << name << ": terminated by a signal";
        EXPECT_EQ(WEXITSTATUS(status), 2) << name;
        std::ifstream in(err);
        std::string line, text;
        int lines = 0;
        while (std::getline(in, line)) {
            ++lines;
            text += line;
        }
        EXPECT_EQ(lines, 1) << name << ": " << text;
        EXPECT_EQ(text.rfind("tessera: error: ", 0), 0u) << name << ": " << text;
        EXPECT_NE(text.find(name), std::string::npos) << name << ": the message does not name the file: " << text;
        EXPECT_FALSE(fs::exists(exr)) << name;
    }
    EXPECT_GE(files, 20);
}

TEST(MalformedCorpus, ExternalFilesNeedAnExplicitOption) {
    namespace fs = std::filesystem;
    // A scene whose buffer lives in the parent folder: refused by default, accepted when allowed.
    fs::path dir = tessera::test::tempDir("external-files");
    fs::create_directories(dir / "scene");
    fs::copy_file(tessera::test::sourcePath("scenes/cornell-box/cornell-box.bin"), dir / "cornell-box.bin");
    std::ifstream in(tessera::test::sourcePath("scenes/cornell-box/cornell-box.gltf"));
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    size_t p = text.find("\"cornell-box.bin\"");
    ASSERT_NE(p, std::string::npos);
    text.replace(p, 17, "\"../cornell-box.bin\"");
    std::ofstream(dir / "scene" / "box.gltf") << text;
    std::string base = std::string(TESSERA_BINARY) + " render '" + (dir / "scene" / "box.gltf").string() +
                       "' --quiet --spp 1 --resolution 16x16 --no-png -o '" + (dir / "o.exr").string() + "' 2>/dev/null";
    int refused = std::system(base.c_str());
    ASSERT_TRUE(WIFEXITED(refused));
    EXPECT_EQ(WEXITSTATUS(refused), 2);
    int allowed = std::system((base + " --allow-external-files").c_str());
    ASSERT_TRUE(WIFEXITED(allowed));
    EXPECT_EQ(WEXITSTATUS(allowed), 0);
    EXPECT_TRUE(fs::exists(dir / "o.exr"));
}
