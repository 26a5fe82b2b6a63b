#include "core/distribution.h"

#include <algorithm>
#include <cmath>

namespace tessera {

Distribution1D::Distribution1D(std::span<const float> weights) {
    const size_t n = weights.size();
    func_.resize(n);
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) {
        float w = weights[i];
        func_[i] = std::isfinite(w) && w > 0.f ? w : 0.f;
        sum += func_[i];
    }
    integral_ = n > 0 ? sum / double(n) : 0.0;
    if (!(sum > 0.0)) {
        // Nothing to prefer: uniform, so that a sample always exists.
        std::fill(func_.begin(), func_.end(), 1.f);
        sum = double(n);
    }
    pmf_.resize(n);
    cdf_.assign(n + 1, 0.0);
    for (size_t i = 0; i < n; ++i) {
        double p = double(func_[i]) / sum;
        pmf_[i] = float(p);
        cdf_[i + 1] = cdf_[i] + p;
    }
    if (n > 0) cdf_[n] = 1.0;
}

uint32_t Distribution1D::sampleDiscrete(float u, float* uRemapped) const {
    const size_t n = func_.size();
    // The first cell whose upper CDF bound exceeds u: cdf_[i] ≤ u < cdf_[i + 1], so its pmf is > 0.
    size_t i = size_t(std::upper_bound(cdf_.begin() + 1, cdf_.end(), double(u)) - (cdf_.begin() + 1));
    i = std::min(i, n - 1);
    while (pmf_[i] == 0.f && i > 0) --i;  // u at or above 1 (rounding): the last cell of positive weight
    if (uRemapped) {
        double width = cdf_[i + 1] - cdf_[i];
        double r = width > 0.0 ? (double(u) - cdf_[i]) / width : 0.0;
        *uRemapped = float(std::clamp(r, 0.0, double(0x1.fffffep-1f)));
    }
    return uint32_t(i);
}

float Distribution1D::sampleContinuous(float u, float& pdf, uint32_t& cell) const {
    float du;
    cell = sampleDiscrete(u, &du);
    const float n = float(func_.size());
    pdf = pmf_[cell] * n;
    return std::min((float(cell) + du) / n, 0x1.fffffep-1f);
}

float Distribution1D::pdf(float x) const {
    if (!(x >= 0.f && x < 1.f) || func_.empty()) return 0.f;
    size_t i = std::min(size_t(x * float(func_.size())), func_.size() - 1);
    return pmf_[i] * float(func_.size());
}

Distribution2D::Distribution2D(std::span<const float> weights, int nu, int nv) {
    conditional_.reserve(size_t(nv));
    std::vector<float> rowIntegrals(static_cast<size_t>(nv), 0.f);
    for (int v = 0; v < nv; ++v) {
        conditional_.emplace_back(weights.subspan(size_t(v) * size_t(nu), size_t(nu)));
        rowIntegrals[size_t(v)] = float(conditional_.back().integral());
    }
    marginal_ = Distribution1D(rowIntegrals);
}

void Distribution2D::sample(float u0, float u1, float& u, float& v, float& pdf) const {
    float pdfV, pdfU;
    uint32_t row, col;
    v = marginal_.sampleContinuous(u1, pdfV, row);
    u = conditional_[row].sampleContinuous(u0, pdfU, col);
    pdf = pdfV * pdfU;
}

float Distribution2D::pdf(float u, float v) const {
    if (!(v >= 0.f && v < 1.f) || conditional_.empty()) return 0.f;
    size_t row = std::min(size_t(v * float(conditional_.size())), conditional_.size() - 1);
    return marginal_.pdf(v) * conditional_[row].pdf(u);
}

}  // namespace tessera
