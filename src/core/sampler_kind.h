#pragma once
/// \file sampler_kind.h
/// Which random numbers a render draws (`--sampler`; core/sampler.h has the samplers). Its own
/// header so that settings can name a kind without depending on the sampler's code.
#include <cstdint>
#include <optional>
#include <string_view>

namespace tessera {

enum class SamplerKind : uint8_t { Sobol, Independent };

// Independent stays the default until BDPT's unidirectional strategy (s = 0) finds the SDS caustic
// of `sds-caustic` with the Sobol' sampler as it does with independent numbers (see writeup,
// "Samplers": with sobol, s = 0 found 1.7e-6 of the 167 that ptnee finds there at 32 spp).
inline constexpr SamplerKind kDefaultSampler = SamplerKind::Independent;

inline std::string_view samplerName(SamplerKind k) { return k == SamplerKind::Sobol ? "sobol" : "independent"; }
inline std::optional<SamplerKind> parseSamplerKind(std::string_view name) {
    if (name == "sobol") return SamplerKind::Sobol;
    if (name == "independent") return SamplerKind::Independent;
    return std::nullopt;
}

}  // namespace tessera
