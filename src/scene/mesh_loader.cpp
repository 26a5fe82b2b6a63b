#include "scene/mesh_loader.h"

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "core/error.h"
#include "scene/gltf_loader.h"

namespace tessera {
namespace {

/// Whole file as bytes; gzread passes uncompressed files through unchanged, so one path serves both.
std::string readMaybeGzipped(const std::string& path) {
    gzFile f = gzopen(path.c_str(), "rb");
    if (!f) throw SceneError(path, "", "cannot open file");
    std::string data;
    char buf[1 << 16];
    int n;
    while ((n = gzread(f, buf, sizeof buf)) > 0) data.append(buf, size_t(n));
    bool failed = n < 0;
    gzclose(f);
    if (failed) throw SceneError(path, "", "read error (corrupt gzip stream?)");
    return data;
}

enum class PlyType { Int8, Uint8, Int16, Uint16, Int32, Uint32, Float32, Float64 };

PlyType parsePlyType(const std::string& path, const std::string& t) {
    if (t == "char" || t == "int8") return PlyType::Int8;
    if (t == "uchar" || t == "uint8") return PlyType::Uint8;
    if (t == "short" || t == "int16") return PlyType::Int16;
    if (t == "ushort" || t == "uint16") return PlyType::Uint16;
    if (t == "int" || t == "int32") return PlyType::Int32;
    if (t == "uint" || t == "uint32") return PlyType::Uint32;
    if (t == "float" || t == "float32") return PlyType::Float32;
    if (t == "double" || t == "float64") return PlyType::Float64;
    throw SceneError(path, "header", "unknown PLY property type '" + t + "'");
}

size_t plyTypeSize(PlyType t) {
    switch (t) {
        case PlyType::Int8: case PlyType::Uint8: return 1;
        case PlyType::Int16: case PlyType::Uint16: return 2;
        case PlyType::Int32: case PlyType::Uint32: case PlyType::Float32: return 4;
        case PlyType::Float64: return 8;
    }
    return 0;
}

struct PlyProperty {
    std::string name;
    bool isList = false;
    PlyType countType = PlyType::Uint8, type = PlyType::Float32;
};

struct PlyElement {
    std::string name;
    size_t count = 0;
    std::vector<PlyProperty> properties;
};

/// Reads values of any PLY type from ASCII tokens or binary bytes of either endianness.
class PlyReader {
public:
    PlyReader(const std::string& path, const std::string& data, size_t pos, int format)
        : path_(path), data_(data), pos_(pos), format_(format) {}

    double read(PlyType t) {
        if (format_ == 0) return readAscii();
        size_t size = plyTypeSize(t);
        if (pos_ + size > data_.size()) throw SceneError(path_, "body", "file ends early");
        unsigned char bytes[8];
        std::memcpy(bytes, data_.data() + pos_, size);
        pos_ += size;
        bool fileBig = format_ == 2, hostBig = std::endian::native == std::endian::big;
        if (fileBig != hostBig) std::reverse(bytes, bytes + size);
        switch (t) {
            case PlyType::Int8: return double(int8_t(bytes[0]));
            case PlyType::Uint8: return double(bytes[0]);
            case PlyType::Int16: { int16_t v; std::memcpy(&v, bytes, 2); return v; }
            case PlyType::Uint16: { uint16_t v; std::memcpy(&v, bytes, 2); return v; }
            case PlyType::Int32: { int32_t v; std::memcpy(&v, bytes, 4); return v; }
            case PlyType::Uint32: { uint32_t v; std::memcpy(&v, bytes, 4); return v; }
            case PlyType::Float32: { float v; std::memcpy(&v, bytes, 4); return v; }
            case PlyType::Float64: { double v; std::memcpy(&v, bytes, 8); return v; }
        }
        return 0.0;
    }

private:
    double readAscii() {
        while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
        if (pos_ >= data_.size()) throw SceneError(path_, "body", "file ends early");
        double v = 0.0;
        auto [end, ec] = std::from_chars(data_.data() + pos_, data_.data() + data_.size(), v);
        if (ec != std::errc()) throw SceneError(path_, "body", "not a number near byte " + std::to_string(pos_));
        pos_ = size_t(end - data_.data());
        return v;
    }

    const std::string& path_;
    const std::string& data_;
    size_t pos_;
    int format_;  // 0 ascii, 1 binary little endian, 2 binary big endian
};

void addPolygon(TriangleMesh& mesh, const std::vector<uint32_t>& poly) {
    for (size_t k = 2; k < poly.size(); ++k) mesh.triangles.emplace_back(poly[0], poly[k - 1], poly[k]);
}

void checkIndices(const std::string& path, const TriangleMesh& mesh) {
    for (const glm::uvec3& t : mesh.triangles)
        if (t.x >= mesh.positions.size() || t.y >= mesh.positions.size() || t.z >= mesh.positions.size())
            throw SceneError(path, "faces", "vertex index out of range");
}

std::string lowerExtension(const std::string& path) {
    std::string p = path;
    std::transform(p.begin(), p.end(), p.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (p.size() > 3 && p.ends_with(".gz")) p.resize(p.size() - 3);
    return std::filesystem::path(p).extension().string();
}

}  // namespace

TriangleMesh loadPlyMesh(const std::string& path) {
    std::string data = readMaybeGzipped(path);
    if (!data.starts_with("ply")) throw SceneError(path, "", "not a PLY file");
    size_t headerEnd = data.find("end_header");
    if (headerEnd == std::string::npos) throw SceneError(path, "header", "no end_header");
    size_t bodyStart = data.find('\n', headerEnd);
    if (bodyStart == std::string::npos) throw SceneError(path, "header", "no data after end_header");
    ++bodyStart;

    std::istringstream header(data.substr(0, headerEnd));
    std::vector<PlyElement> elements;
    int format = -1;
    std::string line;
    while (std::getline(header, line)) {
        std::istringstream ls(line);
        std::string word;
        ls >> word;
        if (word == "format") {
            std::string f;
            ls >> f;
            format = f == "ascii" ? 0 : f == "binary_little_endian" ? 1 : f == "binary_big_endian" ? 2 : -1;
            if (format < 0) throw SceneError(path, "header", "unknown format '" + f + "'");
        } else if (word == "element") {
            PlyElement e;
            ls >> e.name >> e.count;
            elements.push_back(e);
        } else if (word == "property") {
            if (elements.empty()) throw SceneError(path, "header", "property before any element");
            PlyProperty p;
            std::string t;
            ls >> t;
            if (t == "list") {
                std::string ct, it;
                ls >> ct >> it >> p.name;
                p.isList = true;
                p.countType = parsePlyType(path, ct);
                p.type = parsePlyType(path, it);
            } else {
                p.type = parsePlyType(path, t);
                ls >> p.name;
            }
            elements.back().properties.push_back(p);
        }
    }
    if (format < 0) throw SceneError(path, "header", "no format line");

    TriangleMesh mesh;
    mesh.name = std::filesystem::path(path).filename().string();
    PlyReader reader(path, data, bodyStart, format);
    std::vector<uint32_t> poly;
    for (const PlyElement& e : elements) {
        bool isVertex = e.name == "vertex", isFace = e.name == "face";
        int xi = -1, yi = -1, zi = -1;
        for (int i = 0; i < int(e.properties.size()); ++i) {
            if (e.properties[i].name == "x") xi = i;
            if (e.properties[i].name == "y") yi = i;
            if (e.properties[i].name == "z") zi = i;
        }
        if (isVertex && (xi < 0 || yi < 0 || zi < 0)) throw SceneError(path, "vertex", "needs x, y and z");
        if (isVertex) mesh.positions.reserve(e.count);
        if (isFace) mesh.triangles.reserve(e.count);
        for (size_t n = 0; n < e.count; ++n) {
            Vec3f pos(0.f);
            bool faceDone = false;
            for (int i = 0; i < int(e.properties.size()); ++i) {
                const PlyProperty& p = e.properties[i];
                if (p.isList) {
                    size_t k = size_t(reader.read(p.countType));
                    bool indices = isFace && !faceDone && (p.name == "vertex_indices" || p.name == "vertex_index");
                    poly.clear();
                    for (size_t j = 0; j < k; ++j) {
                        double v = reader.read(p.type);
                        if (indices) {
                            if (v < 0) throw SceneError(path, "face " + std::to_string(n), "negative vertex index");
                            poly.push_back(uint32_t(v));
                        }
                    }
                    if (indices) addPolygon(mesh, poly), faceDone = true;
                } else {
                    double v = reader.read(p.type);
                    if (isVertex && i == xi) pos.x = float(v);
                    if (isVertex && i == yi) pos.y = float(v);
                    if (isVertex && i == zi) pos.z = float(v);
                }
            }
            if (isVertex) mesh.positions.push_back(pos);
        }
    }
    checkIndices(path, mesh);
    return mesh;
}

TriangleMesh loadObjMesh(const std::string& path) {
    std::string data = readMaybeGzipped(path);
    TriangleMesh mesh;
    mesh.name = std::filesystem::path(path).filename().string();
    std::istringstream in(data);
    std::string line;
    std::vector<uint32_t> poly;
    size_t lineNo = 0;
    while (std::getline(in, line)) {
        ++lineNo;
        std::istringstream ls(line);
        std::string tag;
        ls >> tag;
        if (tag == "v") {
            Vec3f p;
            if (!(ls >> p.x >> p.y >> p.z)) throw SceneError(path, "line " + std::to_string(lineNo), "bad vertex");
            mesh.positions.push_back(p);
        } else if (tag == "f") {
            poly.clear();
            std::string item;
            while (ls >> item) {
                long idx = std::strtol(item.c_str(), nullptr, 10);  // "i", "i/t", "i/t/n", "i//n"
                if (idx < 0) idx += long(mesh.positions.size()) + 1;  // relative to the vertices so far
                if (idx <= 0) throw SceneError(path, "line " + std::to_string(lineNo), "bad face index '" + item + "'");
                poly.push_back(uint32_t(idx - 1));
            }
            addPolygon(mesh, poly);
        }
    }
    checkIndices(path, mesh);
    return mesh;
}

SceneGeometry loadGeometryFile(const std::string& path, std::optional<CameraDesc>& camera,
                               std::vector<std::string>& warnings) {
    std::string ext = lowerExtension(path);
    SceneGeometry g;
    if (ext == ".gltf" || ext == ".glb") {
        Scene scene = loadGltfScene(path, warnings);
        camera = scene.camera;
        g.meshes = std::move(scene.geometry.meshes);
        g.spheres = std::move(scene.geometry.spheres);
    } else if (ext == ".ply") {
        g.meshes.push_back(loadPlyMesh(path));
    } else if (ext == ".obj") {
        g.meshes.push_back(loadObjMesh(path));
    } else {
        throw InputError(path + ": unknown file type (expected .gltf, .glb, .ply, .ply.gz or .obj)");
    }
    return g;
}

}  // namespace tessera
