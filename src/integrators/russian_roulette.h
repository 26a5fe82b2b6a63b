#pragma once
/// \file russian_roulette.h
/// Russian roulette (Arvo & Kirk 1990): a path survives a bounce with probability q and its
/// throughput is divided by q, so the expected contribution is unchanged; since q > 0 whenever the
/// throughput is non-zero, no path with a non-zero contribution gets zero probability. The MIS
/// weights of ptnee and BDPT leave q out: they only need to sum to one over the strategies
/// (Veach 1997, §9.2.2), which they do.
///
/// What q looks at: the throughput gained since the last roulette, with refractions' 1/η² radiance
/// scaling undone (pbrt-v4 §14.1.5), so that paths inside glass are not killed for a scaling that
/// reverses when they leave. Short paths carry most of the image and are never cut: pt and ptnee
/// play from depth kRouletteMinDepth, sub-paths (lt, bdpt, vcm) from their second vertex that
/// scattered with a non-delta lobe on. Delta vertices do not count: a floor seen in a mirror is
/// treated as a floor seen directly. Its SDS paths (camera → mirror → floor → mirror → light)
/// are sampled only by s = 0 and dominate such images' error; a roulette at the floor multiplied
/// their second moment by 1/q (measured in docs/perf-log.md, 2026-11-28).
#include "core/math.h"
#include "core/sampler.h"
#include "integrators/sample_trace.h"

namespace tessera {

/// The depth (surface hits so far, minus one) from which pt and ptnee play roulette.
inline constexpr int kRouletteMinDepth = 2;

/// The roulette of `pt`, `lt` and `bdpt`: `rrScale` is the product of the BSDF weights' largest
/// components (times η² for radiance) since the last roulette. Survives with q = min(1, rrScale),
/// drawing one number only when rrScale < 1; on survival divides `beta` by q and restarts rrScale.
/// `trace` (may be null) records the survival probability.
inline bool survivesRoulette(float& rrScale, Rgb& beta, Sampler& sampler, SampleTrace* trace) {
    if (!(rrScale < 1.f)) return true;
    if (trace) [[unlikely]] trace->add("rrSurvival", rrScale);
    if (sampler.get1D() >= rrScale) return false;
    beta /= rrScale;
    rrScale = 1.f;
    return true;
}

/// The roulette of `ptnee`: the same rule written on the whole throughput, q = 1 − max(0, 1 − rr)
/// with rr = max(β)·etaScale (etaScale: product of η² over refractions). It rounds differently
/// from survivesRoulette, so merging the two would change ptnee's images in their last bits.
inline bool survivesThroughputRoulette(float rr, Rgb& beta, Sampler& sampler, SampleTrace* trace) {
    if (!(rr < 1.f)) return true;
    float q = std::max(0.f, 1.f - rr);
    if (trace) [[unlikely]] trace->add("rrSurvival", 1.f - q);
    if (sampler.get1D() < q) return false;
    beta /= 1.f - q;
    return true;
}

}  // namespace tessera
