#pragma once
/// \file image_output.h
/// Writing rendered images (float EXR, display-referred PNG) and reading any image back as float
/// RGBA, through OpenImageIO. Writes are atomic: a crash, a full disk or a bad path never leaves
/// a half-written or clobbered file at the destination.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace tessera::io {

class DisplayTransform;

/// String attributes stored in an image file, in order, e.g. {"tessera:spp", "1024"}.
using Metadata = std::vector<std::pair<std::string, std::string>>;

/// A decoded image: packed RGBA float, rows top to bottom, `rgba.size() == 4 * width * height`.
struct Image {
    int width = 0, height = 0;
    std::vector<float> rgba;
    /// Every attribute OIIO reports for the file, converted to text; includes format-specific
    /// ones (e.g. "compression") besides the ones the writer put there.
    Metadata metadata;
};

/// Writes `width` x `height` packed RGBA float pixels (scene-linear, unclamped) to a 32-bit float
/// RGBA OpenEXR file with ZIP compression; each `metadata` entry becomes a string attribute.
/// Missing parent directories are created. Throws tessera::InputError naming `path` and the cause
/// on any failure, in which case the previous file at `path` (if any) is left untouched.
void writeExr(const std::string& path, int width, int height, const float* rgba,
              const Metadata& metadata);

/// Writes an 8-bit sRGB-display PNG: a copy of the scene-linear `rgba` goes through `transform`,
/// is clamped to [0,1] and rounded to the nearest 8-bit level (no dithering). Written as opaque
/// RGB: the renderer's alpha carries no coverage a PNG viewer should composite with.
/// `metadata` becomes PNG text chunks. Same atomicity, directory creation and errors as writeExr.
void writePng(const std::string& path, int width, int height, const float* rgba,
              const DisplayTransform& transform, const Metadata& metadata);

/// The PNG's pixels: `rgba` through `transform`, clamped and rounded to 8 bits, packed RGB rows from
/// the top (what writePng stores, and what `tessera view` shows in its window).
std::vector<std::uint8_t> displayRgb8(int width, int height, const float* rgba, const DisplayTransform& transform);

/// Reads the first subimage of any file OIIO can open, converted to float RGBA: one channel is
/// replicated to R, G and B; two channels are read as grey + alpha; with no alpha channel, alpha
/// is 1. Only the data window is returned. Throws tessera::InputError naming `path` if the file
/// cannot be opened or decoded.
Image readImage(const std::string& path);

}  // namespace tessera::io
