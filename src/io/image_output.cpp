#include "io/image_output.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "core/atomic_file.h"
#include "core/error.h"
#include "io/display_transform.h"

namespace tessera::io {

namespace {

namespace fs = std::filesystem;

void checkArguments(const std::string& path, int width, int height, const float* rgba) {
    // A caller bug, not user input: the renderer never produces an empty film.
    if (width <= 0 || height <= 0 || rgba == nullptr) {
        throw std::invalid_argument(path + ": image write with size " + std::to_string(width) +
                                    "x" + std::to_string(height) + " or no pixels");
    }
}

/// Writes one image described by `spec` (pixels of type spec.format, packed) to `path` atomically
/// (core/atomic_file.h). The format is chosen from `path`'s extension, not the temporary name's.
void writeAtomically(const std::string& path, const OIIO::ImageSpec& spec, const void* pixels) {
    writeFileAtomically(path, "file", [&](const std::string& tmpPath) {
        std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path);
        if (!out) {
            throw InputError(path + ": cannot write this image format: " + OIIO::geterror());
        }
        auto fail = [&](const char* what) {
            std::string detail = out->geterror();
            if (detail.empty()) detail = OIIO::geterror();
            throw InputError(path + ": " + what + ": " + detail);
        };
        if (!out->open(tmpPath, spec)) fail("cannot open for writing");
        if (!out->write_image(spec.format, pixels)) fail("cannot write pixels");
        // close() flushes: a full disk is often only reported here.
        if (!out->close()) fail("cannot finish writing");
    });
}

void addMetadata(OIIO::ImageSpec& spec, const Metadata& metadata) {
    for (const auto& [name, value] : metadata) spec.attribute(name, value);
}

/// Nearest 8-bit level of a display value; NaN (which survives clamping) becomes black.
std::uint8_t quantize(float value) {
    if (!(value > 0.0f)) return 0;
    if (value >= 1.0f) return 255;
    return static_cast<std::uint8_t>(value * 255.0f + 0.5f);
}

}  // namespace

void writeExr(const std::string& path, int width, int height, const float* rgba,
              const Metadata& metadata) {
    checkArguments(path, width, height, rgba);
    OIIO::ImageSpec spec(width, height, 4, OIIO::TypeDesc::FLOAT);  // Names R, G, B, A.
    // Lossless and readable everywhere; explicit so output never depends on OIIO's default.
    spec.attribute("compression", "zip");
    addMetadata(spec, metadata);
    writeAtomically(path, spec, rgba);
}

std::vector<std::uint8_t> displayRgb8(int width, int height, const float* rgba, const DisplayTransform& transform) {
    const std::size_t pixelCount = std::size_t(width) * std::size_t(height);
    std::vector<float> display(rgba, rgba + 4 * pixelCount);
    transform.apply(display.data(), width, height);

    std::vector<std::uint8_t> rgb(3 * pixelCount);
    for (std::size_t i = 0; i < pixelCount; ++i) {
        for (int c = 0; c < 3; ++c) rgb[3 * i + c] = quantize(display[4 * i + c]);
    }
    return rgb;
}

void writePng(const std::string& path, int width, int height, const float* rgba,
              const DisplayTransform& transform, const Metadata& metadata) {
    checkArguments(path, width, height, rgba);
    std::vector<std::uint8_t> rgb = displayRgb8(width, height, rgba, transform);

    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    addMetadata(spec, metadata);
    writeAtomically(path, spec, rgb.data());
}

Image readImage(const std::string& path) {
    // ImageInput, not ImageBuf: an ImageBuf reads through OIIO's process-wide ImageCache, which
    // keeps serving a file's old pixels when it is rewritten within the same second (a resumed
    // render's output read back by the test that read the interrupted one).
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
    if (!in) {
        std::string detail = OIIO::geterror();
        throw InputError(path + ": cannot read image: " + (detail.empty() ? "unknown format" : detail));
    }
    const OIIO::ImageSpec spec = in->spec();
    const int channels = spec.nchannels;
    const int alpha = spec.alpha_channel;
    if (spec.width <= 0 || spec.height <= 0 || channels <= 0)
        throw InputError(path + ": cannot read image: empty or channel-less image");
    std::vector<float> pixels(std::size_t(spec.width) * std::size_t(spec.height) * std::size_t(channels));
    if (!in->read_image(/* subimage = */ 0, /* miplevel = */ 0, 0, channels, OIIO::TypeDesc::FLOAT, pixels.data())) {
        throw InputError(path + ": cannot read pixels: " + in->geterror());
    }
    in->close();

    // A source channel per RGBA output channel; -1 takes the constant from `fill`.
    int order[4] = {0, 1, 2, alpha};
    const float fill[4] = {0.0f, 0.0f, 0.0f, 1.0f};
    if (channels < 3) {
        // Grey or grey + alpha. A lone channel is grey even if its name says alpha.
        order[0] = order[1] = order[2] = 0;
        order[3] = (channels == 2) ? 1 : -1;
    } else if (alpha < 3) {
        order[3] = -1;  // No alpha, or an "alpha" among the first three: treat as opaque RGB.
    }

    Image image;
    image.width = spec.width;
    image.height = spec.height;
    const std::size_t n = std::size_t(image.width) * std::size_t(image.height);
    image.rgba.resize(4 * n);
    for (std::size_t p = 0; p < n; ++p)
        for (int c = 0; c < 4; ++c)
            image.rgba[4 * p + c] = order[c] >= 0 ? pixels[p * std::size_t(channels) + std::size_t(order[c])] : fill[c];
    for (const OIIO::ParamValue& param : spec.extra_attribs) {
        image.metadata.emplace_back(param.name().string(), param.get_string());
    }
    return image;
}

}  // namespace tessera::io
