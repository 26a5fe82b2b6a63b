// Malformed scenes give a clear error naming file, element and problem; the CLI exits with 2.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <fstream>

#include "core/error.h"
#include "scene/gltf_loader.h"
#include "test_helpers.h"

using namespace tessera;

namespace {

const char* kValidTriangle = R"({
  "asset": {"version": "2.0"},
  "scene": 0, "scenes": [{"nodes": [0, 1]}],
  "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0, 0, 3]}],
  "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "buffers": [{"byteLength": 48, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAEAAAACAAAA"}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 12}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
    {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}]
})";

std::string writeScene(const std::string& dir, const std::string& name, const std::string& text) {
    std::string path = dir + "/" + name;
    std::ofstream(path) << text;
    return path;
}

std::string replaced(std::string s, const std::string& from, const std::string& to) {
    size_t p = s.find(from);
    EXPECT_NE(p, std::string::npos) << from;
    if (p != std::string::npos) s.replace(p, from.size(), to);
    return s;
}

/// Loads and returns the error message ("" when it loaded).
std::string loadError(const std::string& path) {
    std::vector<std::string> warnings;
    try {
        loadGltfScene(path, warnings);
    } catch (const SceneError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(SceneErrors, ValidBaseSceneLoads) {
    std::string dir = test::tempDir("scene-errors-valid").string();
    std::vector<std::string> warnings;
    Scene s = loadGltfScene(writeScene(dir, "ok.gltf", kValidTriangle), warnings);
    ASSERT_EQ(s.geometry.meshes.size(), 1u);
    EXPECT_EQ(s.geometry.meshes[0].triangles.size(), 1u);
    EXPECT_TRUE(s.camera.has_value());
}

TEST(SceneErrors, EachDefectIsNamed) {
    std::string dir = test::tempDir("scene-errors").string();
    struct Case {
        std::string name, text, expectElement, expectProblem;
    };
    std::vector<Case> cases = {
        {"truncated.gltf", std::string(kValidTriangle).substr(0, 200), "parse error at line 5", "invalid glTF"},
        {"index-range.gltf", replaced(kValidTriangle, "AEAAAACAAAA", "AEAAAAJAAAA"), "meshes[0].primitives[0]", "out of range"},
        {"short-view.gltf", replaced(kValidTriangle, "\"count\": 3, \"type\": \"VEC3\"", "\"count\": 30, \"type\": \"VEC3\""), "accessors[0]", "exceeds its bufferView"},
        {"bad-type.gltf", replaced(kValidTriangle, "\"type\": \"VEC3\"", "\"type\": \"VEC2\""), "accessors[0]", "unexpected accessor type"},
        {"required-ext.gltf", replaced(kValidTriangle, "\"asset\"", "\"extensionsUsed\": [\"EXT_magic\"], \"extensionsRequired\": [\"EXT_magic\"], \"asset\""),
         "extensionsRequired", "EXT_magic"},
        {"missing-buffer.gltf", replaced(kValidTriangle, "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAEAAAACAAAA", "nowhere.bin"), "nowhere.bin", "File not found"},
        {"negative-radius.gltf", replaced(kValidTriangle, "{\"mesh\": 0}", "{\"extensions\": {\"TESSERA_sphere\": {\"radius\": -1}}}"),
         "nodes[0].extensions.TESSERA_sphere", "radius"},
        {"bad-fov.gltf", replaced(kValidTriangle, "\"yfov\": 0.8", "\"yfov\": -0.8"), "cameras[0]", "yfov"},
        {"node-cycle.gltf", replaced(kValidTriangle, "{\"mesh\": 0}", "{\"mesh\": 0, \"children\": [0]}"), "nodes[0]", "reachable twice"},
        {"bad-resolution.gltf", replaced(kValidTriangle, "\"asset\"", "\"extensions\": {\"TESSERA_render\": {\"resolution\": [0, 10]}}, \"asset\""),
         "extensions.TESSERA_render", "resolution"},
    };
    for (const Case& c : cases) {
        std::string path = writeScene(dir, c.name, c.text);
        std::string msg = loadError(path);
        EXPECT_FALSE(msg.empty()) << c.name << " loaded without error";
        EXPECT_NE(msg.find(c.name), std::string::npos) << c.name << ": message does not name the file: " << msg;
        EXPECT_NE(msg.find(c.expectElement), std::string::npos) << c.name << ": " << msg;
        EXPECT_NE(msg.find(c.expectProblem), std::string::npos) << c.name << ": " << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << c.name << ": message spans lines: " << msg;
    }
    EXPECT_NE(loadError(dir + "/does-not-exist.gltf").find("no such file"), std::string::npos);
}

TEST(SceneErrors, CommandLineExitsWithTwoAndOneLine) {
    std::string dir = test::tempDir("scene-errors-cli").string();
    std::string bad = writeScene(dir, "broken.gltf", "{ \"asset\": ");
    std::string noCamera = writeScene(dir, "nocam.gltf", replaced(kValidTriangle, "\"nodes\": [0, 1]", "\"nodes\": [0]"));
    for (const std::string& scene : {bad, noCamera}) {
        std::string cmd = std::string(TESSERA_BINARY) + " render " + scene + " --quiet -o " + dir + "/x.exr 2> " + dir + "/err.txt";
        int status = std::system(cmd.c_str());
        ASSERT_TRUE(WIFEXITED(status)) << "killed by a signal: " << cmd;
        EXPECT_EQ(WEXITSTATUS(status), 2) << cmd;
        std::ifstream in(dir + "/err.txt");
        std::string line, all;
        int lines = 0;
        while (std::getline(in, line)) {
            ++lines;
            all += line;
        }
        EXPECT_EQ(lines, 1) << all;
        EXPECT_NE(all.find("tessera: error: "), std::string::npos) << all;
        EXPECT_NE(all.find(scene), std::string::npos) << all;
        EXPECT_FALSE(std::filesystem::exists(dir + "/x.exr"));
    }
}
