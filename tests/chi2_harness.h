#pragma once
// The χ² goodness-of-fit harness of the sampling tests (pbrt / Nori style): directions binned over
// (cos θ, φ), expected cell probabilities integrated from a density, Pearson's χ² with small cells
// pooled. Used by test_sampling_chi2.cpp and test_gltf_bsdf.cpp; each file Šidák-corrects its own
// family of tests.
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include "core/math.h"

namespace tessera::test {

constexpr int kThetaBins = 16, kPhiBins = 32;

/// Upper-tail p-value of χ² with `dof` degrees of freedom by the Wilson–Hilferty cube-root normal
/// approximation (Wilson & Hilferty 1931), accurate to ~1e-3 in p for dof ≳ 10.
inline double chi2PValue(double chi2, int dof) {
    double k = dof;
    double z = (std::cbrt(chi2 / k) - (1.0 - 2.0 / (9.0 * k))) / std::sqrt(2.0 / (9.0 * k));
    return 0.5 * std::erfc(z / std::sqrt(2.0));
}

/// Direction → cell over (cos θ ∈ [−1, 1], φ ∈ [0, 2π)) of the z-up frame.
inline int cellOf(const Vec3f& w) {
    float phi = std::atan2(w.y, w.x);
    if (phi < 0.f) phi += 2.f * kPi;
    int it = std::clamp(int((w.z + 1.f) * 0.5f * kThetaBins), 0, kThetaBins - 1);
    int ip = std::clamp(int(phi * kInv2Pi * kPhiBins), 0, kPhiBins - 1);
    return it * kPhiBins + ip;
}

/// Expected probability of every cell: ∫ pdfW dω with dω = d(cos θ) dφ, by a midpoint rule.
inline std::vector<double> integrateCells(const std::function<double(const Vec3f&)>& pdfW, int sub = 12) {
    std::vector<double> p(size_t(kThetaBins * kPhiBins), 0.0);
    double dz = 2.0 / (kThetaBins * sub), dphi = 2.0 * kPi / (kPhiBins * sub);
    for (int it = 0; it < kThetaBins * sub; ++it) {
        double z = -1.0 + (it + 0.5) * dz;
        double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        for (int ip = 0; ip < kPhiBins * sub; ++ip) {
            double phi = (ip + 0.5) * dphi;
            Vec3f w(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
            p[size_t((it / sub) * kPhiBins + ip / sub)] += pdfW(w) * dz * dphi;
        }
    }
    return p;
}

/// Pearson χ² of observed counts (the last entry: failed samples) against expected probabilities,
/// cells with expectation < 5 pooled (Nori's χ² test). Returns the p-value; fails the test if a
/// cell of zero expectation received samples.
inline double chi2Test(const std::vector<int>& counts, std::vector<double> prob, int n, const std::string& what) {
    double total = 0.0;
    for (double p : prob) total += p;
    prob.push_back(std::max(0.0, 1.0 - total));  // the failure cell
    double chi2 = 0.0, pooledObs = 0.0, pooledExp = 0.0;
    int dof = -1, zeroCellHits = 0;
    for (size_t i = 0; i < counts.size(); ++i) {
        double e = prob[i] * n;
        if (e < 1e-9 && counts[i] > 0) zeroCellHits += counts[i];
        if (e < 5.0) {
            pooledObs += counts[i];
            pooledExp += e;
            continue;
        }
        chi2 += (counts[i] - e) * (counts[i] - e) / e;
        ++dof;
    }
    if (pooledExp >= 5.0) {
        chi2 += (pooledObs - pooledExp) * (pooledObs - pooledExp) / pooledExp;
        ++dof;
    }
    EXPECT_LE(zeroCellHits, n / 20000) << what << ": samples where the pdf integrates to zero";
    return dof > 0 ? chi2PValue(chi2, dof) : 1.0;
}

}  // namespace tessera::test
