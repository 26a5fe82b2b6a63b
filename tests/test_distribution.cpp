// The piecewise-constant distributions of core/distribution.h (light selection, environment
// sampling): zero-weight cells are never chosen, the densities integrate to one and match the
// sampled frequencies, and degenerate inputs (all zero, NaN, negative) stay usable.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "core/distribution.h"
#include "core/rng.h"

using namespace tessera;

TEST(Distribution1D, DiscreteSamplingFollowsTheWeightsAndSkipsZeros) {
    const std::vector<float> w = {0.f, 2.f, 0.f, 0.f, 6.f, 1.f, 0.f, -3.f, std::numeric_limits<float>::quiet_NaN(), 1.f};
    Distribution1D d(w);
    EXPECT_NEAR(d.integral(), 10.0 / 10.0, 1e-12);
    const double expect[] = {0, 0.2, 0, 0, 0.6, 0.1, 0, 0, 0, 0.1};
    for (size_t i = 0; i < w.size(); ++i) EXPECT_NEAR(d.pmf(i), expect[i], 1e-7) << i;
    std::vector<int> counts(w.size(), 0);
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
        float remapped = -1.f;
        uint32_t c = d.sampleDiscrete((float(i) + 0.5f) / float(n), &remapped);
        ASSERT_LT(c, w.size());
        ASSERT_GE(remapped, 0.f);
        ASSERT_LT(remapped, 1.f);
        ++counts[c];
    }
    for (size_t i = 0; i < w.size(); ++i) EXPECT_NEAR(counts[i] / double(n), expect[i], 1e-4) << i;
    // The edges: u = 0 and the largest float below 1 land on cells of positive weight.
    EXPECT_EQ(d.sampleDiscrete(0.f), 1u);
    EXPECT_EQ(d.sampleDiscrete(0x1.fffffep-1f), 9u);
    EXPECT_EQ(d.sampleDiscrete(1.f), 9u);
}

TEST(Distribution1D, AllZeroWeightsBecomeUniform) {
    Distribution1D d(std::vector<float>{0.f, 0.f, 0.f, 0.f});
    EXPECT_EQ(d.integral(), 0.0);
    for (size_t i = 0; i < 4; ++i) EXPECT_FLOAT_EQ(d.pmf(i), 0.25f);
    EXPECT_EQ(d.sampleDiscrete(0.6f), 2u);
}

TEST(Distribution2D, ContinuousDensityIntegratesToOneAndMatchesSamples) {
    const int nu = 8, nv = 4;
    std::vector<float> w(size_t(nu * nv));
    for (int v = 0; v < nv; ++v)
        for (int u = 0; u < nu; ++u) w[size_t(v * nu + u)] = (u == 5 && v == 1) ? 40.f : (v == 3 ? 0.f : 1.f + float(u));
    Distribution2D d(w, nu, nv);
    // ∫ pdf = 1 by the midpoint rule on a grid finer than the cells.
    double sum = 0.0;
    const int g = 64;
    for (int j = 0; j < g; ++j)
        for (int i = 0; i < g; ++i) sum += d.pdf((i + 0.5f) / g, (j + 0.5f) / g) / double(g * g);
    EXPECT_NEAR(sum, 1.0, 1e-5);
    // Sampled cell frequencies equal each cell's pdf × its area; the reported pdf is pdf(u, v).
    Pcg32 rng(3, 5);
    std::vector<int> counts(w.size(), 0);
    const int n = 400000;
    for (int i = 0; i < n; ++i) {
        float u, v, pdf;
        d.sample(rng.nextFloat(), rng.nextFloat(), u, v, pdf);
        ASSERT_TRUE(u >= 0.f && u < 1.f && v >= 0.f && v < 1.f);
        ASSERT_NEAR(pdf, d.pdf(u, v), 1e-4f * pdf);
        ++counts[size_t(int(v * nv) * nu + int(u * nu))];
    }
    for (int c = 0; c < nu * nv; ++c) {
        double p = d.pdf((float(c % nu) + 0.5f) / nu, (float(c / nu) + 0.5f) / nv) / double(nu * nv);
        EXPECT_NEAR(counts[size_t(c)] / double(n), p, 5.0 * std::sqrt(p * (1 - p) / n) + 1e-9) << "cell " << c;
        if (w[size_t(c)] == 0.f) {
            EXPECT_EQ(counts[size_t(c)], 0) << "cell " << c;
        }
    }
}
