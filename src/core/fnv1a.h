#pragma once
/// \file fnv1a.h
/// FNV-1a, 64-bit (Fowler, Noll, Vo; the IETF draft "The FNV Non-Cryptographic Hash Algorithm"):
/// the one hash Tessera uses to identify inputs and structures, e.g. a scene file in an image's
/// metadata. Not cryptographic: it detects change, not tampering.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>

namespace tessera {

inline constexpr uint64_t kFnv1a64Offset = 0xcbf29ce484222325ULL;
inline constexpr uint64_t kFnv1a64Prime = 0x100000001b3ULL;

/// Continues hash `h` over `bytes` bytes at `data` (start with kFnv1a64Offset).
inline uint64_t fnv1a64(const void* data, size_t bytes, uint64_t h = kFnv1a64Offset) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * kFnv1a64Prime;
    return h;
}

/// "fnv1a64:<16 hex digits>" of a file's bytes (of nothing when it cannot be read): the form
/// written as `tessera:scene_hash` into images and checkpoints.
inline std::string fnv1a64OfFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    uint64_t h = kFnv1a64Offset;
    char buf[1 << 16];
    while (in.read(buf, sizeof buf) || in.gcount() > 0) h = fnv1a64(buf, size_t(in.gcount()), h);
    char out[32];
    std::snprintf(out, sizeof out, "fnv1a64:%016llx", static_cast<unsigned long long>(h));
    return out;
}

}  // namespace tessera
