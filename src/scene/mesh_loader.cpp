#include "scene/mesh_loader.h"

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string_view>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>

#include "core/error.h"

namespace tessera {
namespace {

/// A number for messages: integers without decimals, others with enough digits to recognise.
std::string num(double v) {
    char buf[40];
    bool exactInteger = v == std::floor(v) && std::abs(v) < 9007199254740992.0;  // 2^53
    std::snprintf(buf, sizeof buf, exactInteger ? "%.0f" : "%.9g", v);
    return buf;
}

std::string gib(uint64_t bytes) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g GiB", double(bytes) / double(uint64_t(1) << 30));
    return buf;
}

/// Whole file as bytes; gzread passes uncompressed files through unchanged, so one path serves both.
/// Stops at `maxBytes` (a gzip bomb decompresses without bound otherwise).
std::string readMaybeGzipped(const std::string& path, uint64_t maxBytes) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw SceneError(path, "", "cannot open file (missing or not a regular file)");
    gzFile f = gzopen(path.c_str(), "rb");
    if (!f) throw SceneError(path, "", std::string("cannot open file: ") + std::strerror(errno));
    std::string data;
    char buf[1 << 16];
    int n;
    while ((n = gzread(f, buf, sizeof buf)) > 0) {
        if (data.size() + size_t(n) > maxBytes) {
            gzclose(f);
            throw SceneError(path, "", "data exceeds the memory limit of " + gib(maxBytes) + " (after decompression)");
        }
        data.append(buf, size_t(n));
    }
    // A stream cut short reads as a clean end of file but leaves Z_BUF_ERROR behind.
    int code = Z_OK;
    const char* msg = gzerror(f, &code);
    std::string failure;
    if (n < 0 || (code != Z_OK && code != Z_STREAM_END)) {
        std::string detail = msg ? msg : "read error";
        if (detail.starts_with(path + ": ")) detail.erase(0, path.size() + 2);  // zlib prefixes the path
        failure = "corrupt or truncated gzip stream (" + detail + ")";
    }
    gzclose(f);
    if (!failure.empty()) throw SceneError(path, "", failure);
    return data;
}

enum class PlyType { Int8, Uint8, Int16, Uint16, Int32, Uint32, Float32, Float64 };

PlyType parsePlyType(const std::string& path, const std::string& where, const std::string& t) {
    if (t == "char" || t == "int8") return PlyType::Int8;
    if (t == "uchar" || t == "uint8") return PlyType::Uint8;
    if (t == "short" || t == "int16") return PlyType::Int16;
    if (t == "ushort" || t == "uint16") return PlyType::Uint16;
    if (t == "int" || t == "int32") return PlyType::Int32;
    if (t == "uint" || t == "uint32") return PlyType::Uint32;
    if (t == "float" || t == "float32") return PlyType::Float32;
    if (t == "double" || t == "float64") return PlyType::Float64;
    throw SceneError(path, where, "unknown PLY property type '" + t + "'");
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

bool isIntegerType(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

struct PlyProperty {
    std::string name;
    bool isList = false;
    PlyType countType = PlyType::Uint8, type = PlyType::Float32;
};

struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

/// Reads values of any PLY type from ASCII tokens or binary bytes of either endianness. Errors
/// name the element and row being read.
class PlyReader {
public:
    PlyReader(const std::string& path, const std::string& data, size_t pos, int format)
        : path_(path), data_(data), pos_(pos), format_(format) {}

    void setRow(const std::string& element, uint64_t row) {
        element_ = &element;
        row_ = row;
    }
    [[noreturn]] void fail(const std::string& problem) const {
        throw SceneError(path_, "element " + *element_ + ", row " + std::to_string(row_), problem);
    }
    size_t bytesLeft() const { return data_.size() - pos_; }

    double read(PlyType t) {
        double v = format_ == 0 ? readAscii() : readBinary(t);
        if (isIntegerType(t) && format_ == 0 && v != std::floor(v)) failNotInteger(v);
        return v;
    }

private:
    // Out of line: inlined into every reader, the message's concatenation trips GCC 12's -Wrestrict
    // false positive (GCC bug 105329).
    [[noreturn]] __attribute__((noinline)) void failNotInteger(double v) const { fail("'" + num(v) + "' is not an integer"); }

    double readBinary(PlyType t) {
        size_t size = plyTypeSize(t);
        if (size > bytesLeft()) fail("file ends early (truncated)");
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
    double readAscii() {
        while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
        if (pos_ >= data_.size()) fail("file ends early (truncated)");
        double v = 0.0;
        auto [end, ec] = std::from_chars(data_.data() + pos_, data_.data() + data_.size(), v);
        if (ec == std::errc::result_out_of_range) fail("number out of range near byte " + std::to_string(pos_));
        if (ec != std::errc()) {
            size_t stop = pos_;
            while (stop < data_.size() && stop - pos_ < 20 && !std::isspace(static_cast<unsigned char>(data_[stop]))) ++stop;
            fail("'" + data_.substr(pos_, stop - pos_) + "' is not a number (byte " + std::to_string(pos_) + ")");
        }
        pos_ = size_t(end - data_.data());
        return v;
    }

    const std::string& path_;
    const std::string& data_;
    size_t pos_;
    int format_;  // 0 ascii, 1 binary little endian, 2 binary big endian
    const std::string* element_ = nullptr;
    uint64_t row_ = 0;
};

void addPolygon(TriangleMesh& mesh, const std::vector<uint32_t>& poly) {
    for (size_t k = 2; k < poly.size(); ++k) mesh.triangles.emplace_back(poly[0], poly[k - 1], poly[k]);
}

/// A non-negative integer header field ("element vertex 8"); anything else is an error.
uint64_t parseCount(const std::string& path, const std::string& where, const std::string& text) {
    uint64_t v = 0;
    auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (text.empty() || ec != std::errc() || end != text.data() + text.size())
        throw SceneError(path, where, "element count '" + text + "' is not a non-negative integer");
    return v;
}

/// Smallest number of bytes one row of `e` can take: binary sizes, or one digit and one separator
/// per ASCII value (a list at least its count).
uint64_t minimumRowBytes(const PlyElement& e, int format) {
    uint64_t n = 0;
    for (const PlyProperty& p : e.properties) n += format == 0 ? 2 : plyTypeSize(p.isList ? p.countType : p.type);
    return n;
}

struct PlyHeader {
    int format = -1;
    std::vector<PlyElement> elements;
    size_t bodyStart = 0;
};

PlyHeader parsePlyHeader(const std::string& path, const std::string& data) {
    if (!data.starts_with("ply")) throw SceneError(path, "", "not a PLY file (no 'ply' magic line)");
    PlyHeader h;
    size_t pos = 0;
    for (int lineNo = 1;; ++lineNo) {
        if (pos >= data.size()) throw SceneError(path, "header", "no end_header line (file truncated?)");
        size_t eol = data.find('\n', pos);
        if (eol == std::string::npos) throw SceneError(path, "header line " + std::to_string(lineNo), "file ends inside the header");
        std::string line = data.substr(pos, eol - pos);
        pos = eol + 1;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        std::string where = "header line " + std::to_string(lineNo);
        std::istringstream ls(line);
        std::string word;
        ls >> word;
        if (word == "end_header") break;
        if (word == "format") {
            std::string f;
            ls >> f;
            h.format = f == "ascii" ? 0 : f == "binary_little_endian" ? 1 : f == "binary_big_endian" ? 2 : -1;
            if (h.format < 0) throw SceneError(path, where, "unknown format '" + f + "'");
        } else if (word == "element") {
            PlyElement e;
            std::string count;
            if (!(ls >> e.name >> count)) throw SceneError(path, where, "'element' needs a name and a count");
            e.count = parseCount(path, where, count);
            h.elements.push_back(e);
        } else if (word == "property") {
            if (h.elements.empty()) throw SceneError(path, where, "property before any element");
            PlyProperty p;
            std::string t;
            ls >> t;
            if (t == "list") {
                std::string ct, it;
                ls >> ct >> it >> p.name;
                p.isList = true;
                p.countType = parsePlyType(path, where, ct);
                p.type = parsePlyType(path, where, it);
                if (!isIntegerType(p.countType)) throw SceneError(path, where, "list count type '" + ct + "' is not an integer type");
            } else {
                p.type = parsePlyType(path, where, t);
                ls >> p.name;
            }
            if (p.name.empty()) throw SceneError(path, where, "property without a name");
            h.elements.back().properties.push_back(p);
        } else if (word != "comment" && word != "obj_info" && !word.empty() && word != "ply") {
            throw SceneError(path, where, "unknown header keyword '" + word + "'");
        }
    }
    if (h.format < 0) throw SceneError(path, "header", "no format line");
    h.bodyStart = pos;
    return h;
}

/// Allocation bombs: a declared count must fit both the bytes the file has and the memory limit.
/// Returns the `vertex` element's count when the file declares one.
std::optional<uint64_t> checkDeclaredCounts(const std::string& path, const PlyHeader& header, uint64_t bodyBytes,
                                            uint64_t maxBytes) {
    uint64_t minimumBody = 0;
    std::optional<uint64_t> vertexCount;
    for (const PlyElement& e : header.elements) {
        std::string where = "element " + e.name;
        uint64_t row = minimumRowBytes(e, header.format);
        if (row > 0 && e.count > (bodyBytes - std::min(bodyBytes, minimumBody)) / row)
            throw SceneError(path, where,
                             "declares " + std::to_string(e.count) + " rows, but the " + std::to_string(bodyBytes) +
                                 " bytes of data after the header hold at most " +
                                 std::to_string((bodyBytes - std::min(bodyBytes, minimumBody)) / row) + " (truncated file or bad count)");
        minimumBody += e.count * row;
        uint64_t perRow = e.name == "vertex" ? sizeof(Vec3f) : e.name == "face" ? sizeof(glm::uvec3) : 0;
        if (perRow > 0 && e.count > maxBytes / perRow)
            throw SceneError(path, where, std::to_string(e.count) + " rows need more than the memory limit of " + gib(maxBytes));
        if (e.name == "vertex") vertexCount = e.count;
    }
    return vertexCount;
}

/// Reads one list property of the current row. When `indices`, its items are a face's vertex
/// indices: checked against `vertexCount` and stored in `poly`. Returns the list's length.
size_t readPlyList(PlyReader& reader, const PlyProperty& p, bool indices, std::optional<uint64_t> vertexCount,
                   std::vector<uint32_t>& poly) {
    double count = reader.read(p.countType);
    if (count < 0) reader.fail("negative list length " + num(count));
    // Every item takes at least one byte: a count beyond the data left is a lie.
    if (count > double(reader.bytesLeft())) reader.fail("list length " + num(count) + " exceeds the data left");
    size_t k = size_t(count);
    poly.clear();
    for (size_t j = 0; j < k; ++j) {
        double v = reader.read(p.type);
        if (!indices) continue;
        if (!(v >= 0) || v != std::floor(v)) reader.fail("vertex index " + num(v) + " is not a non-negative integer");
        // Compared as doubles and printed with num(): converting an out-of-range double
        // to an integer is undefined behaviour (found by tools/fuzz.sh).
        if ((vertexCount && v >= double(*vertexCount)) || v > double(0xfffffffeu))
            reader.fail("vertex index " + num(v) + " out of range (the file has " + std::to_string(vertexCount.value_or(0)) +
                        " vertices)");
        poly.push_back(uint32_t(v));
    }
    return k;
}

/// Reads every row of element `e`: vertex positions and face index lists go into `mesh`, other
/// elements and properties are read past.
void readPlyElement(const std::string& path, PlyReader& reader, const PlyElement& e, std::optional<uint64_t> vertexCount,
                    TriangleMesh& mesh) {
    bool isVertex = e.name == "vertex", isFace = e.name == "face";
    int xi = -1, yi = -1, zi = -1;
    for (int i = 0; i < int(e.properties.size()); ++i) {
        if (e.properties[i].name == "x") xi = i;
        if (e.properties[i].name == "y") yi = i;
        if (e.properties[i].name == "z") zi = i;
    }
    if (isVertex && (xi < 0 || yi < 0 || zi < 0)) throw SceneError(path, "element vertex", "needs properties x, y and z");
    if (isVertex && (e.properties[xi].isList || e.properties[yi].isList || e.properties[zi].isList))
        throw SceneError(path, "element vertex", "x, y and z must not be lists");
    if (isVertex) mesh.positions.reserve(size_t(e.count));
    if (isFace) mesh.triangles.reserve(size_t(e.count));
    std::vector<uint32_t> poly;
    for (uint64_t n = 0; n < e.count; ++n) {
        reader.setRow(e.name, n);
        Vec3f pos(0.f);
        bool faceDone = false;
        for (int i = 0; i < int(e.properties.size()); ++i) {
            const PlyProperty& p = e.properties[i];
            if (p.isList) {
                bool indices = isFace && !faceDone && (p.name == "vertex_indices" || p.name == "vertex_index");
                size_t k = readPlyList(reader, p, indices, vertexCount, poly);
                if (indices) {
                    if (k < 3) reader.fail("face with " + std::to_string(k) + " vertices (at least 3 needed)");
                    addPolygon(mesh, poly);
                    faceDone = true;
                }
            } else {
                double v = reader.read(p.type);
                if (isVertex && (i == xi || i == yi || i == zi)) {
                    // Checked before the conversion: a double beyond float range makes float(v) undefined.
                    if (!(std::abs(v) <= double(std::numeric_limits<float>::max())))
                        reader.fail("non-finite coordinate " + p.name + " = " + num(v) + (std::isfinite(v) ? " (beyond float range)" : ""));
                    (i == xi ? pos.x : i == yi ? pos.y : pos.z) = float(v);
                }
            }
        }
        if (isVertex) mesh.positions.push_back(pos);
    }
}

}  // namespace

TriangleMesh loadPlyMesh(const std::string& path, const MeshLoadOptions& options) {
    std::string data = readMaybeGzipped(path, options.maxBytes);
    PlyHeader header = parsePlyHeader(path, data);
    std::optional<uint64_t> vertexCount = checkDeclaredCounts(path, header, data.size() - header.bodyStart, options.maxBytes);

    TriangleMesh mesh;
    mesh.name = std::filesystem::path(path).filename().string();
    PlyReader reader(path, data, header.bodyStart, header.format);
    bool sawVertex = false, sawFace = false;
    for (const PlyElement& e : header.elements) {
        sawVertex |= e.name == "vertex";
        sawFace |= e.name == "face";
        readPlyElement(path, reader, e, vertexCount, mesh);
    }
    if (!sawVertex) throw SceneError(path, "header", "no 'vertex' element");
    if (!sawFace) throw SceneError(path, "header", "no 'face' element (point clouds cannot be traced)");
    return mesh;
}

TriangleMesh loadObjMesh(const std::string& path, const MeshLoadOptions& options) {
    std::string data = readMaybeGzipped(path, options.maxBytes);
    TriangleMesh mesh;
    mesh.name = std::filesystem::path(path).filename().string();
    std::vector<uint32_t> poly;
    // OBJ lets a face name vertices defined further down: check those at the end, with their line.
    std::vector<std::pair<size_t, uint64_t>> forwardReferences;  // (line, largest index)
    size_t lineNo = 0, pos = 0;
    auto fail = [&](const std::string& problem) -> void { throw SceneError(path, "line " + std::to_string(lineNo), problem); };
    while (pos < data.size()) {
        size_t eol = data.find('\n', pos);
        if (eol == std::string::npos) eol = data.size();
        std::string_view line(data.data() + pos, eol - pos);
        pos = eol + 1;
        ++lineNo;
        auto next = [&](size_t& i) {  // next whitespace-separated token of the line
            while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
            size_t b = i;
            while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
            return line.substr(b, i - b);
        };
        size_t i = 0;
        std::string_view tag = next(i);
        if (tag == "v") {
            float xyz[3];
            for (float& c : xyz) {
                std::string_view t = next(i);
                auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), c);
                if (ec == std::errc::result_out_of_range) fail("vertex coordinate '" + std::string(t) + "' is beyond float range");
                if (t.empty() || ec != std::errc() || end != t.data() + t.size())
                    fail("bad vertex coordinate '" + std::string(t) + "' (need 'v x y z')");
                if (!std::isfinite(c)) fail("non-finite vertex coordinate '" + std::string(t) + "'");
            }
            if (mesh.positions.size() >= options.maxBytes / sizeof(Vec3f)) fail("vertices exceed the memory limit of " + gib(options.maxBytes));
            mesh.positions.emplace_back(xyz[0], xyz[1], xyz[2]);
        } else if (tag == "f") {
            poly.clear();
            uint64_t largest = 0;
            for (std::string_view item = next(i); !item.empty(); item = next(i)) {
                std::string_view first = item.substr(0, item.find('/'));  // "i", "i/t", "i/t/n", "i//n"
                int64_t idx = 0;
                auto [end, ec] = std::from_chars(first.data(), first.data() + first.size(), idx);
                if (first.empty() || ec != std::errc() || end != first.data() + first.size() || idx == 0)
                    fail("bad face index '" + std::string(item) + "'");
                if (idx < 0) idx += int64_t(mesh.positions.size()) + 1;  // relative to the vertices so far
                if (idx <= 0) fail("relative face index '" + std::string(item) + "' points before the first vertex");
                if (idx > int64_t(0xffffffffu)) fail("face index '" + std::string(item) + "' out of range");
                largest = std::max(largest, uint64_t(idx));
                poly.push_back(uint32_t(idx - 1));
            }
            if (poly.size() < 3) fail("face with " + std::to_string(poly.size()) + " vertices (at least 3 needed)");
            if (largest > mesh.positions.size()) forwardReferences.emplace_back(lineNo, largest);
            addPolygon(mesh, poly);
        }
    }
    for (const auto& [line, largest] : forwardReferences)
        if (largest > mesh.positions.size())
            throw SceneError(path, "line " + std::to_string(line),
                             "face index " + std::to_string(largest) + " out of range (the file has " +
                                 std::to_string(mesh.positions.size()) + " vertices)");
    if (mesh.triangles.empty()) throw SceneError(path, "", "no faces");
    return mesh;
}

}  // namespace tessera
