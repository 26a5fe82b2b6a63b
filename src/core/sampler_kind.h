#pragma once
/// \file sampler_kind.h
/// Which random numbers a render draws (`--sampler`; core/sampler.h has the samplers). Its own
/// header so that settings can name a kind without depending on the sampler's code.
#include <cstdint>
#include <optional>
#include <string_view>

namespace tessera {

enum class SamplerKind : uint8_t { Sobol, Independent };

/// The sampler of `render`, `view` and the tests unless they name one (writeup, "Samplers": on
/// the smooth scenes Sobol' is 1.4-4x ahead at equal time, and no statistical test needs the
/// independent sampler).
inline constexpr SamplerKind kDefaultSampler = SamplerKind::Sobol;

inline std::string_view samplerName(SamplerKind k) { return k == SamplerKind::Sobol ? "sobol" : "independent"; }
inline std::optional<SamplerKind> parseSamplerKind(std::string_view name) {
    if (name == "sobol") return SamplerKind::Sobol;
    if (name == "independent") return SamplerKind::Independent;
    return std::nullopt;
}

}  // namespace tessera
