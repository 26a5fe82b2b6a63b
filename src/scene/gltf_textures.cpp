#include "scene/gltf_textures.h"

#include <filesystem>

#include "core/error.h"

namespace tessera {
namespace {

namespace gl = tinygltf;

/// URIs are percent-encoded (RFC 3986, glTF 2.0 3.3.2); tinygltf decodes them before opening a file,
/// so the path named in a message is decoded the same way.
std::string percentDecoded(const std::string& uri) {
    std::string out;
    for (size_t i = 0; i < uri.size(); ++i) {
        if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
            std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
            out += char(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
            i += 2;
        } else {
            out += uri[i];
        }
    }
    return out;
}

uint64_t imageBytes(const Image& image) {
    uint64_t bytes = 0;
    for (const ImageLevel& l : image.levels) bytes += uint64_t(l.texels.size()) * sizeof(Vec4f);
    return bytes;
}

}  // namespace

bool storeImageBytes(gl::Image* image, int, std::string*, std::string*, int, int, const unsigned char* bytes, int size, void*) {
    if (image->bufferView >= 0) return true;
    if (bytes && size > 0) image->image.assign(bytes, bytes + size);
    return true;
}

/// A textureInfo as a material slot gives it: where to find the texture, which TEXCOORD set, and
/// the KHR_texture_transform object (or null).
struct GltfTextureReader::Slot {
    std::string name;  ///< e.g. "normalTexture", for messages
    int index = -1;
    int texCoord = 0;
    const gl::Value* transform = nullptr;
};

GltfTextureReader::GltfTextureReader(const gl::Model& model, std::string scenePath, std::vector<std::unique_ptr<Image>>& images,
                                     std::vector<std::string>& warnings, std::function<std::string(const std::string&)> whyUnreadable,
                                     uint64_t memoryBudget)
    : model_(model), path_(std::move(scenePath)), images_(images), warnings_(warnings), whyUnreadable_(std::move(whyUnreadable)),
      memoryBudget_(memoryBudget) {}

void GltfTextureReader::fail(const std::string& element, const std::string& problem) const { throw SceneError(path_, element, problem); }

namespace {

const gl::Value* transformOf(const gl::ExtensionMap& extensions) {
    auto it = extensions.find("KHR_texture_transform");
    return it == extensions.end() ? nullptr : &it->second;
}

/// A textureInfo the file gives (tinygltf leaves index at −1 when the slot is absent; any other
/// negative index is the file's and is reported as out of range).
template <class Info>
bool present(const Info& info) {
    return info.index != -1 || !info.extensions.empty();
}

}  // namespace

void GltfTextureReader::readMaterial(const gl::Material& gm, Material& m, const std::string& el) {
    const std::string label = gm.name.empty() ? el : el + " ('" + gm.name + "')";
    auto slotOf = [&](const auto& info, const std::string& name) {
        Slot s;
        s.name = name;
        s.index = info.index;
        s.texCoord = info.texCoord;
        s.transform = transformOf(info.extensions);
        return s;
    };
    // Extension texture slots are plain JSON objects in tinygltf: {index, texCoord, extensions}.
    auto slotOfValue = [&](const gl::Value& ext, const char* key, const std::string& name, Slot& s) {
        if (!ext.IsObject() || !ext.Has(key)) return false;
        const gl::Value& v = ext.Get(key);
        s.name = name;
        if (!v.IsObject()) fail(label + "." + name, "must be an object {index, texCoord}");
        const gl::Value& index = v.Get("index");
        if (!index.IsInt()) fail(label + "." + name, "'index' must be an integer");
        s.index = index.Get<int>();
        if (v.Has("texCoord")) {
            if (!v.Get("texCoord").IsInt()) fail(label + "." + name, "'texCoord' must be an integer");
            s.texCoord = v.Get("texCoord").Get<int>();
        }
        if (v.Has("extensions") && v.Get("extensions").Has("KHR_texture_transform"))
            s.transform = &v.Get("extensions").Get("KHR_texture_transform");
        return true;
    };

    const gl::PbrMetallicRoughness& pbr = gm.pbrMetallicRoughness;
    MaterialTextures& t = m.textures;
    if (present(pbr.baseColorTexture))
        t.baseColor = readTexture(slotOf(pbr.baseColorTexture, "pbrMetallicRoughness.baseColorTexture"), ColorEncoding::Srgb, label);
    if (present(pbr.metallicRoughnessTexture))
        t.metallicRoughness = readTexture(slotOf(pbr.metallicRoughnessTexture, "pbrMetallicRoughness.metallicRoughnessTexture"),
                                          ColorEncoding::Linear, label);
    if (present(gm.normalTexture)) {
        t.normal = readTexture(slotOf(gm.normalTexture, "normalTexture"), ColorEncoding::Linear, label);
        if (!std::isfinite(gm.normalTexture.scale)) fail(label + ".normalTexture", "scale must be finite");
        t.normalScale = float(gm.normalTexture.scale);
    }
    if (present(gm.emissiveTexture))
        t.emissive = readTexture(slotOf(gm.emissiveTexture, "emissiveTexture"), ColorEncoding::Srgb, label);
    // occlusionTexture is not read: ambient occlusion approximates the shadowing that a path tracer
    // computes by tracing rays, so applying it would darken creases twice.
    Slot s;
    if (auto e = gm.extensions.find("KHR_materials_transmission"); e != gm.extensions.end())
        if (slotOfValue(e->second, "transmissionTexture", "extensions.KHR_materials_transmission.transmissionTexture", s))
            t.transmission = readTexture(s, ColorEncoding::Linear, label);
    if (auto e = gm.extensions.find("KHR_materials_specular"); e != gm.extensions.end()) {
        if (slotOfValue(e->second, "specularTexture", "extensions.KHR_materials_specular.specularTexture", s))
            t.specular = readTexture(s, ColorEncoding::Linear, label);
        s = Slot{};
        if (slotOfValue(e->second, "specularColorTexture", "extensions.KHR_materials_specular.specularColorTexture", s))
            t.specularColor = readTexture(s, ColorEncoding::Srgb, label);
    }

    // Alpha (glTF 2.0 3.9.4): baseColorFactor.a × baseColorTexture.a against alphaCutoff.
    const std::vector<double>& bc = pbr.baseColorFactor;
    double alpha = bc.size() >= 4 ? bc[3] : 1.0;
    if (!(alpha >= 0.0 && alpha <= 1.0)) fail(label, "baseColorFactor alpha must be in [0, 1]");
    m.alphaFactor = float(alpha);
    if (gm.alphaMode.empty() || gm.alphaMode == "OPAQUE") {
        m.alphaMode = AlphaMode::Opaque;
    } else if (gm.alphaMode == "MASK") {
        m.alphaMode = AlphaMode::Mask;
        if (!(gm.alphaCutoff >= 0.0) || !std::isfinite(gm.alphaCutoff)) fail(label, "alphaCutoff must be finite and >= 0");
        m.alphaCutoff = float(gm.alphaCutoff);
    } else if (gm.alphaMode == "BLEND") {
        // Blending has no meaning for a path tracer's opaque hits; cut out at half coverage.
        m.alphaMode = AlphaMode::Blend;
        m.alphaCutoff = 0.5f;
        if (!warnedBlend_)
            warnings_.push_back(path_ + ": " + label + " (and any other alphaMode BLEND material): BLEND is rendered as MASK with alphaCutoff 0.5");
        warnedBlend_ = true;
    } else {
        fail(label, "alphaMode '" + gm.alphaMode + "' must be OPAQUE, MASK or BLEND");
    }
}

std::shared_ptr<const AlphaMask> GltfTextureReader::alphaMaskOf(const Material& m) {
    if (m.alphaMode == AlphaMode::Opaque) return nullptr;
    // Without a texture alpha is constant: a mask that keeps everything is no mask.
    if (!m.textures.baseColor.valid() && m.alphaFactor >= m.alphaCutoff) return nullptr;
    auto mask = std::make_shared<AlphaMask>();
    mask->texture = m.textures.baseColor;
    mask->factor = m.alphaFactor;
    mask->cutoff = m.alphaCutoff;
    return mask;
}

TextureRef GltfTextureReader::readTexture(const Slot& slot, ColorEncoding encoding, const std::string& label) {
    const std::string el = label + "." + slot.name;
    if (slot.index < 0 || size_t(slot.index) >= model_.textures.size())
        fail(el, "texture index " + std::to_string(slot.index) + " out of range (" + std::to_string(model_.textures.size()) +
                     " textures)");
    const gl::Texture& tex = model_.textures[size_t(slot.index)];
    const std::string tel = el + " -> " + indexedElement("textures", size_t(slot.index));
    TextureRef ref;

    int texCoord = slot.texCoord;
    if (slot.transform) {
        // KHR_texture_transform: uv' = T(offset) · R(rotation) · S(scale) · uv; its texCoord overrides.
        const gl::Value& v = *slot.transform;
        const std::string xel = el + ".extensions.KHR_texture_transform";
        if (!v.IsObject()) fail(xel, "must be an object");
        auto vec2 = [&](const char* key, Vec2f fallback) {
            if (!v.Has(key)) return fallback;
            const gl::Value& a = v.Get(key);
            if (!a.IsArray() || a.ArrayLen() != 2 || !a.Get(0).IsNumber() || !a.Get(1).IsNumber())
                fail(xel, std::string("'") + key + "' must be an array of 2 numbers");
            Vec2f r(float(a.Get(0).GetNumberAsDouble()), float(a.Get(1).GetNumberAsDouble()));
            if (!isFinite(Vec3f(r, 0.f))) fail(xel, std::string("'") + key + "' must be finite");
            return r;
        };
        ref.transform.offset = vec2("offset", Vec2f(0.f));
        ref.transform.scale = vec2("scale", Vec2f(1.f));
        if (v.Has("rotation")) {
            const gl::Value& r = v.Get("rotation");
            if (!r.IsNumber() || !std::isfinite(r.GetNumberAsDouble())) fail(xel, "'rotation' must be a finite number");
            ref.transform.rotation = float(r.GetNumberAsDouble());
        }
        if (v.Has("texCoord")) {
            if (!v.Get("texCoord").IsInt()) fail(xel, "'texCoord' must be an integer");
            texCoord = v.Get("texCoord").Get<int>();
        }
    }
    if (texCoord < 0 || texCoord > 1)
        fail(el, "texCoord " + std::to_string(texCoord) + " is not supported (TEXCOORD_0 and TEXCOORD_1 only)");
    ref.texCoord = uint8_t(texCoord);

    if (tex.sampler >= 0) {
        if (size_t(tex.sampler) >= model_.samplers.size())
            fail(tel, "sampler index " + std::to_string(tex.sampler) + " out of range (" + std::to_string(model_.samplers.size()) +
                          " samplers)");
        const gl::Sampler& s = model_.samplers[size_t(tex.sampler)];
        const std::string sel = tel + " -> " + indexedElement("samplers", size_t(tex.sampler));
        auto wrap = [&](int mode, const char* key) {
            switch (mode) {
            case TINYGLTF_TEXTURE_WRAP_REPEAT: return WrapMode::Repeat;
            case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT: return WrapMode::MirroredRepeat;
            case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE: return WrapMode::ClampToEdge;
            default: fail(sel, std::string(key) + " " + std::to_string(mode) + " is not a glTF wrap mode (10497, 33648, 33071)");
            }
        };
        ref.wrapS = wrap(s.wrapS, "wrapS");
        ref.wrapT = wrap(s.wrapT, "wrapT");
        if (s.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST) ref.filter = FilterMode::Nearest;
        else if (s.magFilter == TINYGLTF_TEXTURE_FILTER_LINEAR || s.magFilter == -1) ref.filter = FilterMode::Linear;
        else fail(sel, "magFilter " + std::to_string(s.magFilter) + " is not a glTF magnification filter (9728, 9729)");
    }

    if (tex.source < 0) fail(tel, "has no source image (images in texture extensions such as KHR_texture_basisu are not supported)");
    if (size_t(tex.source) >= model_.images.size())
        fail(tel, "image index " + std::to_string(tex.source) + " out of range (" + std::to_string(model_.images.size()) + " images)");
    ref.image = image(tex.source, encoding, tel);
    return ref;
}

const Image* GltfTextureReader::image(int index, ColorEncoding encoding, const std::string& el) {
    if (auto it = decoded_.find({index, encoding}); it != decoded_.end()) return it->second;
    const gl::Image& gi = model_.images[size_t(index)];
    std::string name = indexedElement("images", size_t(index));
    if (!gi.uri.empty()) name += " ('" + gi.uri + "')";
    else if (!gi.name.empty()) name += " ('" + gi.name + "')";
    const std::string iel = el + " -> " + name;

    const unsigned char* bytes = gi.image.data();
    size_t size = gi.image.size();
    if (gi.bufferView >= 0) {
        if (size_t(gi.bufferView) >= model_.bufferViews.size()) fail(iel, "bufferView index out of range");
        const gl::BufferView& bv = model_.bufferViews[size_t(gi.bufferView)];
        if (bv.buffer < 0 || size_t(bv.buffer) >= model_.buffers.size()) fail(iel, "buffer index out of range");
        const gl::Buffer& buf = model_.buffers[size_t(bv.buffer)];
        if (bv.byteOffset > buf.data.size() || bv.byteLength > buf.data.size() - bv.byteOffset)
            fail(iel, "its bufferView exceeds its buffer (" + std::to_string(buf.data.size()) + " bytes)");
        bytes = buf.data.data() + bv.byteOffset;
        size = bv.byteLength;
    } else if (size == 0) {
        if (gi.uri.empty()) fail(iel, "image has no data");
        std::string relative = percentDecoded(gi.uri);
        if (std::filesystem::path(relative).is_absolute() || relative.find(':') != std::string::npos)
            fail(iel, "image URI '" + gi.uri + "' is not a relative path (glTF file URIs are relative to the scene's folder)");
        std::filesystem::path file = std::filesystem::path(path_).parent_path() / relative;
        std::string why = whyUnreadable_(file.string());
        std::error_code ec;
        if (!why.empty()) fail(iel, why);
        if (!std::filesystem::is_regular_file(file, ec)) fail(iel, "image file '" + file.string() + "' not found");
        fail(iel, "image file '" + file.string() + "' cannot be read or is empty");
    }

    ImageDecodeLimits limits;
    uint64_t left = memoryBudget_ > decodedBytes_ ? memoryBudget_ - decodedBytes_ : 0;
    limits.maxBytes = std::min(limits.maxBytes, left);
    Image decoded;
    try {
        decoded = decodeImage(name, bytes, size, encoding, limits);
    } catch (const InputError& e) {
        std::string what = e.what();  // decoders' messages may span lines; the error is one line
        for (char& c : what)
            if (c == '\n') c = ';';
        fail(el, what + (left < ImageDecodeLimits{}.maxBytes ? " (memory left for images under --max-memory: " +
                                                                                     std::to_string(left) + " bytes)"
                                                                               : ""));
    }
    decodedBytes_ += imageBytes(decoded);
    images_.push_back(std::make_unique<Image>(std::move(decoded)));
    decoded_[{index, encoding}] = images_.back().get();
    return images_.back().get();
}

}  // namespace tessera
