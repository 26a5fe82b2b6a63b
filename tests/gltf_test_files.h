#pragma once
// Small glTF files for the texture tests, written from the test code: a PNG encoder (zlib) and a
// glTF builder whose buffer goes to a .bin next to the .gltf, or into a .glb.
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace tessera::test {

/// A PNG (8-bit, `channels` = 1 grey, 3 RGB or 4 RGBA; no interlace) of `pixels`, rows top to bottom.
inline std::string pngBytes(int width, int height, int channels, const std::vector<uint8_t>& pixels) {
    auto be32 = [](uint32_t v) {
        std::string s(4, '\0');
        for (int i = 0; i < 4; ++i) s[size_t(i)] = char((v >> (24 - 8 * i)) & 0xff);
        return s;
    };
    auto chunk = [&](const char* type, const std::string& data) {
        std::string body = std::string(type, 4) + data;
        uLong crc = crc32(0L, reinterpret_cast<const Bytef*>(body.data()), uInt(body.size()));
        return be32(uint32_t(data.size())) + body + be32(uint32_t(crc));
    };
    std::string raw;
    for (int y = 0; y < height; ++y) {
        raw += '\0';  // filter type None
        raw.append(reinterpret_cast<const char*>(pixels.data()) + size_t(y) * size_t(width * channels), size_t(width * channels));
    }
    uLongf zsize = compressBound(uLong(raw.size()));
    std::string z(zsize, '\0');
    compress2(reinterpret_cast<Bytef*>(z.data()), &zsize, reinterpret_cast<const Bytef*>(raw.data()), uLong(raw.size()), 9);
    z.resize(zsize);
    const char colourType = channels == 1 ? 0 : channels == 3 ? 2 : 6;
    std::string ihdr = be32(uint32_t(width)) + be32(uint32_t(height)) + std::string{8, colourType, 0, 0, 0};
    return std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) + chunk("IDAT", z) + chunk("IEND", "");
}

inline std::string base64(const std::string& in) {
    static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    size_t i = 0;
    for (; i + 2 < in.size(); i += 3) {
        uint32_t v = uint32_t(uint8_t(in[i])) << 16 | uint32_t(uint8_t(in[i + 1])) << 8 | uint8_t(in[i + 2]);
        for (int k = 3; k >= 0; --k) out += t[(v >> (6 * k)) & 63];
    }
    if (i + 1 == in.size()) {
        uint32_t v = uint32_t(uint8_t(in[i])) << 16;
        out += std::string{t[(v >> 18) & 63], t[(v >> 12) & 63], '=', '='};
    } else if (i + 2 == in.size()) {
        uint32_t v = uint32_t(uint8_t(in[i])) << 16 | uint32_t(uint8_t(in[i + 1])) << 8;
        out += std::string{t[(v >> 18) & 63], t[(v >> 12) & 63], t[(v >> 6) & 63], '='};
    }
    return out;
}

/// One glTF document with one binary buffer. Accessors are appended with their data; nodes,
/// meshes, materials and the rest are edited directly in `doc`.
struct GltfBuilder {
    nlohmann::json doc = {{"asset", {{"version", "2.0"}}}};
    std::string bin;

    int view(const std::string& bytes) {
        while (bin.size() % 4) bin += '\0';
        doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes.size()}});
        bin += bytes;
        return int(doc["bufferViews"].size()) - 1;
    }
    /// An accessor of `count` elements of `type` ("VEC2", …) with components of glTF type
    /// `componentType` whose little-endian bytes are `bytes`.
    int accessor(const std::string& bytes, size_t count, int componentType, const char* type, bool normalized = false) {
        nlohmann::json a = {{"bufferView", view(bytes)}, {"componentType", componentType}, {"count", count}, {"type", type}};
        if (normalized) a["normalized"] = true;
        doc["accessors"].push_back(a);
        return int(doc["accessors"].size()) - 1;
    }
    template <class T>
    static std::string bytesOf(const std::vector<T>& v) {
        return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    }
    int floats(const std::vector<float>& v, int components, const char* type) {
        return accessor(bytesOf(v), v.size() / size_t(components), 5126, type);
    }
    /// POSITION accessor with the min/max glTF requires.
    int positions(const std::vector<float>& xyz) {
        int a = floats(xyz, 3, "VEC3");
        std::vector<float> lo(3, 1e30f), hi(3, -1e30f);
        for (size_t i = 0; i < xyz.size(); ++i) lo[i % 3] = std::min(lo[i % 3], xyz[i]), hi[i % 3] = std::max(hi[i % 3], xyz[i]);
        doc["accessors"][size_t(a)]["min"] = lo;
        doc["accessors"][size_t(a)]["max"] = hi;
        return a;
    }
    int indices(const std::vector<uint32_t>& ix) { return accessor(bytesOf(ix), ix.size(), 5125, "SCALAR"); }
    /// An image held in a buffer view (GLB style) or as a data URI.
    int image(const std::string& png, bool inBufferView) {
        nlohmann::json im;
        if (inBufferView) im = {{"bufferView", view(png)}, {"mimeType", "image/png"}};
        else im = {{"uri", "data:image/png;base64," + base64(png)}};
        doc["images"].push_back(im);
        return int(doc["images"].size()) - 1;
    }
    int imageFile(const std::string& uri) {
        doc["images"].push_back({{"uri", uri}});
        return int(doc["images"].size()) - 1;
    }
    int texture(int image, int sampler = -1) {
        nlohmann::json t = {{"source", image}};
        if (sampler >= 0) t["sampler"] = sampler;
        doc["textures"].push_back(t);
        return int(doc["textures"].size()) - 1;
    }

    /// Writes `path` (.gltf: the buffer goes to path + ".bin"; .glb: one binary file).
    void write(const std::string& path) {
        while (bin.size() % 4) bin += '\0';
        nlohmann::json d = doc;
        bool glb = path.size() > 4 && path.compare(path.size() - 4, 4, ".glb") == 0;
        if (!bin.empty()) {
            d["buffers"] = nlohmann::json::array();
            nlohmann::json b = {{"byteLength", bin.size()}};
            if (!glb) {
                std::string binName = path.substr(path.find_last_of('/') + 1) + ".bin";
                b["uri"] = binName;
                std::ofstream(path + ".bin", std::ios::binary) << bin;
            }
            d["buffers"].push_back(b);
        }
        std::string json = d.dump();
        if (!glb) {
            std::ofstream(path, std::ios::binary) << json;
            return;
        }
        while (json.size() % 4) json += ' ';
        auto le32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
        std::string out = "glTF" + le32(2) + le32(uint32_t(12 + 8 + json.size() + (bin.empty() ? 0 : 8 + bin.size())));
        out += le32(uint32_t(json.size())) + "JSON" + json;
        if (!bin.empty()) out += le32(uint32_t(bin.size())) + std::string("BIN\0", 4) + bin;
        std::ofstream(path, std::ios::binary) << out;
    }
};

}  // namespace tessera::test
