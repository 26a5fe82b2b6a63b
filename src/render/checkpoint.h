#pragma once
/// \file checkpoint.h
/// Render checkpoints (`render --checkpoint SEC`, `render --resume`): the film's raw sums and the
/// scheduler's RenderState, under a header of every setting that decides the pixels. A render
/// resumed from one continues exactly where it stopped and ends with the same bits as a render
/// that was never interrupted (tests/test_resume.cpp).
///
/// The same file, with the header keys `kind=partial` and `samples=A:B`, is a sample-range partial
/// (`render --samples A:B`, render/partial.h), merged by `tessera merge`.
///
/// File layout (format version 2, the writer's byte order, checked by a byte-order mark):
///   "TESSCKPT", u32 version, u32 0x01020304
///   u64 n, n bytes of header text: one "key=value" line per setting, in the caller's order
///   u64 m, m bytes of payload: u32 width, u32 height, the RenderState, then sum, sum of squares,
///          splats (3 FilmAccum, i.e. 16-byte fixed-point numbers, per pixel each; render/film.h)
///          and the per-pixel u32 sample counts
///   u32 CRC-32 (zlib) of every byte before it
/// Written to a temporary file beside the destination and renamed over it, so a crash or a second
/// Ctrl-C never leaves a half-written checkpoint in its place.
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "render/film.h"
#include "render/renderer.h"

namespace tessera {

/// The settings that decide the pixels, e.g. {"integrator", "bdpt"}, {"seed", "7"}; compared
/// key by key on resume.
using CheckpointHeader = std::vector<std::pair<std::string, std::string>>;

/// Writes `film` and `state` to `path` atomically. Throws InputError naming `path` on failure; the
/// previous checkpoint (if any) is then left untouched.
void writeCheckpoint(const std::string& path, const CheckpointHeader& header, const Film& film,
                     const RenderState& state);

/// Reads the checkpoint at `path` into `film` (which must have the checkpoint's size) and returns
/// the state to continue from. Throws InputError naming `path` and the problem when the file is
/// missing, truncated, corrupt (checksum), of another format version or byte order, or when its
/// header differs from `expected` (naming the first setting that differs and both values).
RenderState readCheckpoint(const std::string& path, const CheckpointHeader& expected, Film& film);

/// Only the header of the checkpoint at `path` (framing checked, checksum not: the full read checks
/// it). InputError naming `path` when it is missing, not a checkpoint or truncated in the header.
CheckpointHeader readCheckpointHeader(const std::string& path);

/// A checkpoint file read without knowing its settings beforehand (`tessera merge`).
struct CheckpointContents {
    CheckpointHeader header;
    RenderState state;
    std::unique_ptr<Film> film;
};

/// Reads the whole file at `path`; refuses, like readCheckpoint, a missing, truncated or corrupt one
/// (InputError naming `path`). Allocates no more than the file's own length can hold.
CheckpointContents readCheckpointContents(const std::string& path);

}  // namespace tessera
