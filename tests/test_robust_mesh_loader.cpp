// Every file of tests/corpus/malformed-mesh (written by tests/corpus/make_malformed_meshes.py)
// makes `tessera validate-accel` fail cleanly: exit code 2, one line "tessera: error: FILE: ..."
// naming the element and row, the header line or the OBJ line, and the problem; no signal.
// The memory limit stops gzip and count bombs before they allocate.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <zlib.h>

#include <fstream>
#include <map>

#include "core/error.h"
#include "scene/mesh_loader.h"
#include "test_helpers.h"

namespace {

namespace fs = std::filesystem;

/// What each file's message must say (besides the file name).
const std::map<std::string, std::string> kExpected = {
    {"truncated-ascii.ply", "element face, row 1: file ends early"},
    {"truncated-binary.ply", "element face, row 1: file ends early"},
    {"no-end-header.ply", "header: no end_header"},
    {"no-magic.ply", "not a PLY file"},
    {"bad-format.ply", "header line 2: unknown format 'binary_middle_endian'"},
    {"no-format.ply", "header: no format line"},
    {"negative-count.ply", "header line 3: element count '-3' is not a non-negative integer"},
    {"non-numeric-count.ply", "header line 3: element count 'four'"},
    {"unknown-type.ply", "header line 4: unknown PLY property type 'float128'"},
    {"float-list-count.ply", "list count type 'float' is not an integer type"},
    {"property-before-element.ply", "header line 3: property before any element"},
    {"missing-z.ply", "element vertex: needs properties x, y and z"},
    {"no-faces.ply", "no 'face' element"},
    {"vertex-count-bomb.ply", "element vertex: declares 4000000000 rows"},
    {"face-count-bomb.ply", "element face: declares 1152921504606846976 rows"},
    {"list-length-bomb.ply", "element face, row 0: list length 4294967295 exceeds the data left"},
    {"index-out-of-range.ply", "element face, row 1: vertex index 4 out of range (the file has 4 vertices)"},
    {"index-huge-binary.ply", "element face, row 0: vertex index 4294967280 out of range"},
    {"negative-index.ply", "element face, row 0: vertex index -1 is not a non-negative integer"},
    {"fractional-index.ply", "element face, row 0: '1.5' is not an integer"},
    {"two-vertex-face.ply", "element face, row 0: face with 2 vertices"},
    {"nan-vertex.ply", "element vertex, row 1: non-finite coordinate y = nan"},
    {"inf-vertex-binary.ply", "element vertex, row 2: non-finite coordinate y = inf"},
    {"overflow-vertex.ply", "element vertex, row 2: non-finite coordinate y = 1e+39 (beyond float range)"},
    {"not-a-number.ply", "element vertex, row 1: 'zero' is not a number"},
    {"bad-gzip.ply.gz", "corrupt or truncated gzip stream"},
    {"truncated-gzip.ply.gz", "corrupt or truncated gzip stream (unexpected end of file)"},
    {"index-out-of-range.obj", "line 5: face index 4 out of range (the file has 3 vertices)"},
    {"index-huge.obj", "line 4: face index '4294967297' out of range"},
    {"relative-before-start.obj", "line 4: relative face index '-4' points before the first vertex"},
    {"zero-index.obj", "line 4: bad face index '0'"},
    {"bad-face-index.obj", "line 4: bad face index 'two'"},
    {"two-vertex-face.obj", "line 4: face with 2 vertices"},
    {"nan-vertex.obj", "line 2: non-finite vertex coordinate 'nan'"},
    {"overflow-vertex.obj", "line 2: vertex coordinate '1e39' is beyond float range"},
    {"short-vertex.obj", "line 2: bad vertex coordinate ''"},
    {"no-faces.obj", "no faces"},
    // Found by tools/fuzz.sh (fuzz_mesh_loader): an ASCII index far beyond uint64 was converted to
    // an integer for the message, undefined behaviour.
    {"fuzz-index-beyond-uint64.ply", "element face, row 58: vertex index 2.18888889e+118 out of range"},
};

struct Outcome {
    int exitCode = -1;
    std::vector<std::string> lines;
};

Outcome validate(const fs::path& input, const fs::path& errFile) {
    std::string cmd = "timeout 60 " + std::string(TESSERA_BINARY) + " validate-accel '" + input.string() + "' --rays 16 2> '" +
                      errFile.string() + "' > /dev/null";
    int status = std::system(cmd.c_str());
    Outcome o;
    EXPECT_TRUE(WIFEXITED(status)) << input << ": terminated by a signal";
    if (WIFEXITED(status)) o.exitCode = WEXITSTATUS(status);
    std::ifstream in(errFile);
    for (std::string line; std::getline(in, line);) o.lines.push_back(line);
    return o;
}

}  // namespace

TEST(MalformedMeshCorpus, EveryFileFailsWithOneLineNamingWhereAndWhat) {
    fs::path corpus = tessera::test::sourcePath("tests/corpus/malformed-mesh");
    fs::path tmp = tessera::test::tempDir("malformed-mesh");
    size_t files = 0;
    for (const auto& entry : fs::directory_iterator(corpus)) {
        std::string name = entry.path().filename().string();
        ++files;
        auto it = kExpected.find(name);
        ASSERT_NE(it, kExpected.end()) << name << " has no expected message in this test";
        Outcome o = validate(entry.path(), tmp / (name + ".err"));
        EXPECT_EQ(o.exitCode, 2) << name;
        ASSERT_EQ(o.lines.size(), 1u) << name;
        const std::string& line = o.lines[0];
        EXPECT_EQ(line.rfind("tessera: error: " + entry.path().string() + ": ", 0), 0u) << line;
        EXPECT_NE(line.find(it->second), std::string::npos) << name << ": expected '" << it->second << "' in: " << line;
    }
    EXPECT_EQ(files, kExpected.size()) << "files listed here are missing from the corpus";

    Outcome missing = validate(corpus / "no-such-file.ply", tmp / "missing.err");
    EXPECT_EQ(missing.exitCode, 2);
    ASSERT_EQ(missing.lines.size(), 1u);
    EXPECT_NE(missing.lines[0].find("no-such-file.ply: cannot open file"), std::string::npos) << missing.lines[0];
}

TEST(MalformedMeshCorpus, MemoryLimitStopsGzipAndCountBombs) {
    using namespace tessera;
    fs::path dir = test::tempDir("mesh-bombs");
    // 8 MiB of zeros compress to a few KiB: refused at the limit, not after inflating it all.
    std::string bomb = (dir / "bomb.ply.gz").string();
    gzFile f = gzopen(bomb.c_str(), "wb9");
    ASSERT_NE(f, nullptr);
    const std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex 699050\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n";
    gzwrite(f, header.data(), unsigned(header.size()));
    std::vector<char> zeros(1 << 20, 0);
    for (int i = 0; i < 8; ++i) gzwrite(f, zeros.data(), unsigned(zeros.size()));
    gzclose(f);
    EXPECT_LT(fs::file_size(bomb), 64u * 1024u);
    MeshLoadOptions limit;
    limit.maxBytes = 1 << 20;
    try {
        loadPlyMesh(bomb, limit);
        ADD_FAILURE() << "no error";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("exceeds the memory limit of 0.000977 GiB (after decompression)"), std::string::npos)
            << e.what();
    }
    // Under the default limit the same file loads (all vertices zero, no faces).
    TriangleMesh m = loadPlyMesh(bomb);
    EXPECT_EQ(m.positions.size(), 699050u);

    // A count the data holds but the memory limit does not.
    std::string many = (dir / "many.ply").string();
    {
        std::ofstream out(many);
        out << "ply\nformat ascii 1.0\nelement vertex 1000\nproperty float x\nproperty float y\nproperty float z\n"
               "element face 0\nproperty list uchar int vertex_indices\nend_header\n";
        for (int i = 0; i < 1000; ++i) out << i << " 0 0\n";
    }
    limit.maxBytes = 1 << 20;
    EXPECT_NO_THROW(loadPlyMesh(many, limit));
    // The file fits the limit (so reading it succeeds) but its 1000 vertices (12000 bytes) do not.
    limit.maxBytes = fs::file_size(many) + 100;
    ASSERT_LT(limit.maxBytes, 12000u);
    try {
        loadPlyMesh(many, limit);
        ADD_FAILURE() << "no error";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("element vertex: 1000 rows need more than the memory limit"), std::string::npos)
            << e.what();
    }
}
