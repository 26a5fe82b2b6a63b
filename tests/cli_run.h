#pragma once
/// \file cli_run.h
/// Running the `tessera` binary from a test (the CLI tests of resume, merge, farm and batch) and
/// comparing the images it writes bit for bit, with their provenance.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <map>
#include <string>

#include "io/image_output.h"

namespace tessera::test {

struct CliRun {
    int code = -1;  ///< exit status; −1 when killed by a signal
    std::string out, err;
};

inline std::string readWholeFile(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Runs `tessera ARGS` in `dir` (at most 120 s), stdout and stderr captured there.
inline CliRun runTessera(const std::filesystem::path& dir, const std::string& args) {
    std::string cmd = "cd '" + dir.string() + "' && timeout 120 " + std::string(TESSERA_BINARY) + " " + args + " > '" +
                      (dir / "stdout.txt").string() + "' 2> '" + (dir / "stderr.txt").string() + "'";
    int status = std::system(cmd.c_str());
    EXPECT_TRUE(WIFEXITED(status)) << cmd << ": terminated by a signal";
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, readWholeFile(dir / "stdout.txt"), readWholeFile(dir / "stderr.txt")};
}

inline std::map<std::string, std::string> imageMetadata(const io::Image& im) {
    std::map<std::string, std::string> m;
    for (const auto& [k, v] : im.metadata) m[k] = v;
    return m;
}

/// Every float of the two EXRs has the same bits, the image is not black, and the metadata `keys`
/// are present and equal in both. Returns both files' metadata for further checks.
inline std::pair<std::map<std::string, std::string>, std::map<std::string, std::string>> expectSameBitsAndProvenance(
    const std::filesystem::path& a, const std::filesystem::path& b, std::initializer_list<const char*> keys) {
    io::Image x = io::readImage(a.string()), y = io::readImage(b.string());
    EXPECT_EQ(x.width, y.width);
    EXPECT_EQ(x.height, y.height);
    EXPECT_EQ(x.rgba.size(), y.rgba.size());
    size_t differing = 0;
    for (size_t i = 0; i < std::min(x.rgba.size(), y.rgba.size()); ++i)
        differing += std::memcmp(&x.rgba[i], &y.rgba[i], sizeof(float)) != 0;
    EXPECT_EQ(differing, 0u) << "floats differing between " << a << " and " << b;
    double sum = 0;
    for (float v : x.rgba) sum += v;
    EXPECT_GT(sum, 0.0);
    auto mx = imageMetadata(x), my = imageMetadata(y);
    for (const char* key : keys) {
        EXPECT_TRUE(mx.count(key)) << key;
        EXPECT_EQ(mx[key], my[key]) << key;
    }
    return {mx, my};
}

}  // namespace tessera::test
