#pragma once
/// \file debug_pixel.h
/// `render --debug-pixel x,y,s`: replays one camera sample exactly as the full render takes it
/// (the same Sampler stream seeded by pixel, sample index and seed, the same raster jitter, the
/// same flush-to-zero mode) and traces it on a stream: every ray the integrator casts through
/// the acceleration structure, what it hits (point, normal, material, emission), every splat,
/// and the first non-finite value met, with where it arose (pbrt-v4's --debugstart).
#include <iosfwd>
#include <vector>

#include "integrators/integrator.h"
#include "render/renderer.h"

namespace tessera {

struct SampleReplay {
    Rgb radiance{0.f};                        ///< the sample's own estimate (what the film would add)
    std::vector<SplatSink::Entry> splats;     ///< its contributions to other pixels
    uint64_t rays = 0;                        ///< closest-hit and shadow rays cast
    size_t vertices = 0;                      ///< trace records: path vertices, sub-path vertices, (s,t) strategies
    bool finite = true;                       ///< radiance and every splat finite
};

/// Replays sample `id` of a render with `seed` and `samplerKind`, writing the trace to `trace`.
SampleReplay replaySample(const RenderContext& ctx, const Integrator& integrator, SampleId id, uint64_t seed,
                          SamplerKind samplerKind, std::ostream& trace);

}  // namespace tessera
