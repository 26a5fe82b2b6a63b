#pragma once
/// \file distribution.h
/// Piecewise-constant distributions, the one home of tabulated sampling: light selection by power
/// (scene/lights.cpp, discrete) and the environment map's luminance × sin θ importance sampling
/// (scene/environment.cpp, continuous 2D). After pbrt-v4 §A.4.3 (PiecewiseConstant1D) and §A.4.4
/// (PiecewiseConstant2D): a function tabulated on n equal cells of [0, 1) is sampled by inverting
/// its running sum (the CDF), so that the density is proportional to the function.
#include <cstdint>
#include <span>
#include <vector>

namespace tessera {

class Distribution1D {
public:
    Distribution1D() = default;
    /// `weights`: one non-negative value per cell (negative and non-finite ones count as 0). When
    /// they are all 0 every cell gets the same weight, so sampling always succeeds.
    explicit Distribution1D(std::span<const float> weights);

    size_t size() const { return func_.size(); }
    bool empty() const { return func_.empty(); }
    /// ∫₀¹ f(x) dx of the tabulated function: the mean of the (clamped) weights; 0 when all were 0.
    double integral() const { return integral_; }

    /// Discrete sampling: cell i with probability pmf(i). A cell of zero weight is never returned.
    /// `uRemapped` (optional) is u rescaled to [0, 1) within the chosen cell, for reuse.
    uint32_t sampleDiscrete(float u, float* uRemapped = nullptr) const;
    float pmf(size_t i) const { return pmf_[i]; }

    /// Continuous sampling of x ∈ [0, 1) with density pdf(x) = f(x) / ∫f (pbrt-v4 §A.4.3); `cell`
    /// receives the cell x lies in.
    float sampleContinuous(float u, float& pdf, uint32_t& cell) const;
    /// The density sampleContinuous has at x (0 outside [0, 1)).
    float pdf(float x) const;

private:
    std::vector<float> func_;  ///< clamped weights (uniform when all were 0)
    std::vector<float> pmf_;   ///< func_ normalised to sum 1
    std::vector<double> cdf_;  ///< cdf_[i] = Σ_{j<i} pmf_j, size n + 1, cdf_[n] = 1
    double integral_ = 0.0;
};

/// A function on [0, 1)² tabulated on nu × nv cells (row-major, v rows): the marginal density of v
/// and the conditional density of u in each row (pbrt-v4 §A.4.4).
class Distribution2D {
public:
    Distribution2D() = default;
    Distribution2D(std::span<const float> weights, int nu, int nv);

    bool empty() const { return conditional_.empty(); }
    double integral() const { return marginal_.integral(); }
    /// (u, v) with density pdf(u, v) = f(u, v) / ∫f.
    void sample(float u0, float u1, float& u, float& v, float& pdf) const;
    float pdf(float u, float v) const;

private:
    std::vector<Distribution1D> conditional_;  ///< one per row v
    Distribution1D marginal_;                  ///< over rows, weighted by each row's integral
};

}  // namespace tessera
