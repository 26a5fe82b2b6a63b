#include "texture/image.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <zlib.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/error.h"

namespace tessera {
namespace {

/// The four formats glTF scenes and environment maps use, recognised by their magic bytes. Only
/// these decoders ever see untrusted bytes: a file that is none of them is refused before any
/// decoder runs (OpenImageIO would otherwise try every format it knows).
const char* sniffFormat(const uint8_t* b, size_t n) {
    if (n >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G') return "png";
    if (n >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return "jpg";
    if (n >= 4 && b[0] == 0x76 && b[1] == 0x2F && b[2] == 0x31 && b[3] == 0x01) return "exr";
    if (n >= 2 && b[0] == '#' && b[1] == '?') return "hdr";  // "#?RADIANCE" / "#?RGBE"
    return nullptr;
}

/// Why a PNG's chunk structure is damaged ("" when intact): every chunk complete, its CRC-32 right,
/// an IEND at the end (PNG specification, 5.3-5.4). OpenImageIO 2.4's PNG reader lets libpng print
/// "libpng error: ..." on stderr for a damaged file before it reports the error itself, so such
/// files are refused here, in one message, before libpng sees them; a CRC covers every byte of a
/// chunk, so any damage to a written file is caught (only a file forged with correct CRCs reaches
/// libpng's own checks).
std::string pngDamage(const uint8_t* b, size_t n) {
    auto be32 = [&](size_t at) { return uint32_t(b[at]) << 24 | uint32_t(b[at + 1]) << 16 | uint32_t(b[at + 2]) << 8 | uint32_t(b[at + 3]); };
    for (size_t at = 8;;) {
        if (n - at < 12) return "truncated: the file ends inside a chunk header";
        uint32_t length = be32(at);
        if (length > n - at - 12) return "truncated: a chunk runs past the end of the file";
        uLong crc = crc32(0L, b + at + 4, uInt(length) + 4u);
        if (uint32_t(crc) != be32(at + 8 + length)) return "corrupt: a chunk's CRC-32 does not match";
        if (std::memcmp(b + at + 4, "IEND", 4) == 0) return "";
        at += 12 + size_t(length);
    }
}

/// sRGB electro-optical transfer function (IEC 61966-2-1), evaluated in double so that each of the
/// 256 8-bit codes decodes to the float nearest the exact value.
double srgbToLinear(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

const std::array<float, 256>& srgb8Table() {
    static const std::array<float, 256> table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i) t[size_t(i)] = float(srgbToLinear(i / 255.0));
        return t;
    }();
    return table;
}

/// code / 255, the float nearest the exact quotient.
const std::array<float, 256>& linear8Table() {
    static const std::array<float, 256> table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i) t[size_t(i)] = float(i / 255.0);
        return t;
    }();
    return table;
}

[[noreturn]] void fail(const std::string& name, const std::string& problem) { throw InputError(name + ": " + problem); }

/// Bytes of a decoded image with all its MIP levels (a level chain sums to < 4/3 of the first).
uint64_t decodedBytes(uint64_t width, uint64_t height) { return width * height * sizeof(Vec4f) * 4 / 3 + sizeof(Vec4f); }

/// Expands `channels` stored values per texel into RGBA the way glTF samples textures:
/// L → (L, L, L, 1), LA → (L, L, L, A), RGB → (R, G, B, 1). Colour channels go through
/// `decodeColor`, alpha through `decodeAlpha` (glTF's alpha is linear coverage, never sRGB).
template <typename DecodeColor, typename DecodeAlpha>
void expandTexels(const std::vector<float>& raw, int channels, DecodeColor decodeColor, DecodeAlpha decodeAlpha,
                  std::vector<Vec4f>& out) {
    const size_t n = out.size();
    for (size_t i = 0; i < n; ++i) {
        const float* s = &raw[i * size_t(channels)];
        Vec4f t;
        if (channels <= 2) {
            float l = decodeColor(s[0]);
            t = Vec4f(l, l, l, channels == 2 ? decodeAlpha(s[1]) : 1.f);
        } else {
            t = Vec4f(decodeColor(s[0]), decodeColor(s[1]), decodeColor(s[2]), channels >= 4 ? decodeAlpha(s[3]) : 1.f);
        }
        // Non-finite texels (a float image may hold them) become 0 here, once, so that no lookup can
        // carry a NaN to the film.
        for (int c = 0; c < 4; ++c)
            if (!std::isfinite(t[c])) t[c] = 0.f;
        out[i] = t;
    }
}

}  // namespace

Image decodeImage(const std::string& name, const uint8_t* bytes, size_t size, ColorEncoding encoding,
                  const ImageDecodeLimits& limits) {
    if (size == 0) fail(name, "image is empty");
    const char* format = sniffFormat(bytes, size);
    if (!format) fail(name, "not a PNG, JPEG, OpenEXR or Radiance HDR image");
    if (std::strcmp(format, "png") == 0)
        if (std::string damage = pngDamage(bytes, size); !damage.empty()) fail(name, "cannot decode png image (" + damage + ")");
    OIIO::Filesystem::IOMemReader reader(bytes, size);
    OIIO::ImageSpec config;
    // glTF textures carry straight (unassociated) alpha: keep it, PNG readers would premultiply.
    config.attribute("oiio:UnassociatedAlpha", 1);
    // OpenImageIO 2.4's readers take the proxy from the configuration (open()'s argument alone is
    // not passed on by every reader).
    void* proxy = &reader;
    config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
    auto in = OIIO::ImageInput::open(std::string("image.") + format, &config, &reader);
    if (!in) {
        std::string err = OIIO::geterror();
        fail(name, "cannot decode " + std::string(format) + " image" + (err.empty() ? "" : " (" + err + ")"));
    }
    // The header is all that has been read: refuse a size over the limits before any pixel buffer
    // exists (an "allocation bomb" header claims billions of pixels in a few bytes).
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.depth != 1) fail(name, "image has an invalid size");
    uint64_t w = uint64_t(spec.width), h = uint64_t(spec.height);
    if (w * h > limits.maxPixels || decodedBytes(w, h) > limits.maxBytes)
        fail(name, "image of " + std::to_string(w) + "x" + std::to_string(h) + " pixels is over the limit (" +
                       std::to_string(limits.maxPixels) + " pixels, " + std::to_string(limits.maxBytes >> 20) + " MiB decoded)");
    int channels = std::min(spec.nchannels, 4);
    if (channels < 1) fail(name, "image has no channels");

    // 8-bit images are read as bytes and decoded through a table, so sRGB decoding is exact; every
    // other depth is read as float (16-bit PNGs convert exactly, float formats are linear already).
    bool eightBit = spec.format == OIIO::TypeDesc::UINT8;
    std::vector<float> raw(size_t(w * h) * size_t(channels));
    bool ok;
    if (eightBit) {
        std::vector<uint8_t> raw8(raw.size());
        ok = in->read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, raw8.data());
        for (size_t i = 0; i < raw.size(); ++i) raw[i] = float(raw8[i]);
    } else {
        ok = in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, raw.data());
    }
    if (!ok) {
        std::string err = in->geterror();
        fail(name, "cannot decode " + std::string(format) + " image (" + (err.empty() ? "truncated or corrupt" : err) + ")");
    }
    in->close();

    Image image;
    image.name = name;
    image.levels.resize(1);
    ImageLevel& level0 = image.levels[0];
    level0.width = int(w);
    level0.height = int(h);
    level0.texels.resize(size_t(w * h));
    const bool srgb = encoding == ColorEncoding::Srgb;
    if (eightBit) {
        // raw holds the codes 0…255: decode each through a table computed in double.
        const std::array<float, 256>& srgbTable = srgb8Table();
        const std::array<float, 256>& linearTable = linear8Table();
        auto code = [](float v) { return size_t(v); };
        expandTexels(
            raw, channels, [&](float v) { return srgb ? srgbTable[code(v)] : linearTable[code(v)]; },
            [&](float v) { return linearTable[code(v)]; }, level0.texels);
    } else {
        expandTexels(
            raw, channels,
            [&](float v) { return srgb ? float(srgbToLinear(std::clamp(double(v), 0.0, 1.0))) : v; },
            [](float v) { return v; }, level0.texels);
    }
    buildMipLevels(image);
    return image;
}

Image readImageFile(const std::string& path, ColorEncoding encoding, const ImageDecodeLimits& limits) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) fail(path, "no such file");
    uint64_t size = std::filesystem::file_size(path, ec);
    if (ec) fail(path, "cannot read the file");
    // An encoded image is never larger than its decoded form plus headers: a file over the decoded
    // limit cannot be a valid image within the limits.
    if (size > limits.maxBytes) fail(path, "file of " + std::to_string(size) + " bytes is over the image limit");
    std::vector<uint8_t> bytes(static_cast<size_t>(size));
    std::ifstream in(path, std::ios::binary);
    if (size > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size))) fail(path, "cannot read the file");
    return decodeImage(path, bytes.data(), bytes.size(), encoding, limits);
}

namespace {

/// One level of the pyramid: each texel of `dst` averages the part of `src` it covers (a box
/// filter with fractional edge weights), so odd sizes are filtered without a shift. Separable:
/// a horizontal pass then a vertical one.
ImageLevel downsample(const ImageLevel& src) {
    ImageLevel dst;
    dst.width = std::max(1, src.width / 2);
    dst.height = std::max(1, src.height / 2);
    // Weights of the source texels covering destination texel i along an axis of n → m texels.
    auto weights = [](int n, int m, int i, std::vector<std::pair<int, float>>& out) {
        out.clear();
        double scale = double(n) / double(m);
        double lo = i * scale, hi = (i + 1) * scale;
        for (int k = int(std::floor(lo)); k < int(std::ceil(hi)) && k < n; ++k) {
            double overlap = std::min(hi, double(k + 1)) - std::max(lo, double(k));
            if (overlap > 0.0) out.emplace_back(k, float(overlap / scale));
        }
    };
    std::vector<Vec4f> rows(size_t(dst.width) * size_t(src.height));
    std::vector<std::pair<int, float>> wts;
    for (int x = 0; x < dst.width; ++x) {
        weights(src.width, dst.width, x, wts);
        for (int y = 0; y < src.height; ++y) {
            Vec4f sum(0.f);
            for (auto [k, wk] : wts) sum += wk * src.at(k, y);
            rows[size_t(y) * size_t(dst.width) + size_t(x)] = sum;
        }
    }
    dst.texels.resize(size_t(dst.width) * size_t(dst.height));
    for (int y = 0; y < dst.height; ++y) {
        weights(src.height, dst.height, y, wts);
        for (int x = 0; x < dst.width; ++x) {
            Vec4f sum(0.f);
            for (auto [k, wk] : wts) sum += wk * rows[size_t(k) * size_t(dst.width) + size_t(x)];
            dst.texels[size_t(y) * size_t(dst.width) + size_t(x)] = sum;
        }
    }
    return dst;
}

}  // namespace

void buildMipLevels(Image& image) {
    if (image.levels.empty()) return;
    image.levels.resize(1);
    while (image.levels.back().width > 1 || image.levels.back().height > 1) {
        ImageLevel next = downsample(image.levels.back());
        image.levels.push_back(std::move(next));
    }
}

}  // namespace tessera
