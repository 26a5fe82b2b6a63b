#pragma once
/// \file partial.h
/// Sample-range partials (`render --samples A:B`) and their merge (`tessera merge`). A partial is
/// a checkpoint file (render/checkpoint.h) whose header holds the render's settings plus
/// `kind=partial` and `samples=A:B`; its film holds samples [A, B) of every pixel. The film's sums
/// are exact (render/film.h), so merging any split of [0, N) gives the bits of one render of N spp.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "render/checkpoint.h"
#include "render/film.h"
#include "render/renderer.h"

namespace tessera {

/// Sample indices [begin, end) of every pixel.
struct SampleRange {
    uint32_t begin = 0, end = 0;
    std::string str() const { return std::to_string(begin) + ":" + std::to_string(end); }
};

/// "A:B" with 0 <= A < B < 2^31; InputError naming `option` otherwise.
SampleRange parseSampleRange(const std::string& text, const std::string& option);

/// Writes samples `range` of a render (its `film` and `stats`) to `path` atomically; `settings` are
/// the render's checkpoint header (every setting that decides the pixels) plus anything to carry
/// into the merged image's metadata.
void writePartial(const std::string& path, const CheckpointHeader& settings, SampleRange range, const Film& film,
                  const RenderStats& stats);

/// Header keys a partial records but the merge does not compare (they never change the pixels).
inline const std::vector<std::string>& partialInformationalKeys() {
    static const std::vector<std::string> keys = {"samples", "scene", "accel", "threads"};
    return keys;
}

struct MergedRender {
    Film film{1, 1};
    CheckpointHeader settings;  ///< the first partial's header without "samples"
    uint32_t spp = 0;           ///< samples per pixel merged (the sum of the ranges' lengths)
    uint32_t sppEnd = 0;        ///< the end of the last range: the N of [0, N)
    uint64_t samples = 0, nonFinite = 0;
    double seconds = 0.0;       ///< render time of all partials together
    std::optional<SampleId> firstNonFinite;
    std::vector<SampleRange> ranges;  ///< merged, by start
    std::vector<SampleRange> gaps;    ///< missing from [0, sppEnd) (only with allowGaps)
};

/// Merges the partials at `paths` (any order) in the order of their range starts. Throws
/// InputError, one line naming the problem, for: a file that is missing, truncated, corrupt or not
/// a partial; partials whose settings differ (naming the setting and both files); overlapping
/// ranges (naming both); and, unless `allowGaps`, missing ranges of [0, N) (naming them).
MergedRender mergePartials(const std::vector<std::string>& paths, bool allowGaps);

}  // namespace tessera
