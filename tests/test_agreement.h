#pragma once
// Agreement of independent integrators on one scene: each renders K batches with different seeds;
// the images are averaged in b×b-pixel bins *per batch* first, so the spread of a bin over the
// batches includes the correlation between pixels that light tracing's and BDPT's splats create
// (one light path lands in several pixels). Each bin and channel then gives a two-sample statistic
// t = (m_A − m_B) / sqrt(s_A²/K + s_B²/K), converted to a normal deviate with Wallace's (1959)
// approximation for Student's t with ν = K − 1 degrees of freedom (conservative: the Welch ν lies
// between K − 1 and 2K − 2), and tested two-sided with a Šidák-corrected level over all of them.
// A bin where both are exactly equal with zero spread (black everywhere) is skipped; a bin where
// one has zero spread and they differ fails.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "test_helpers.h"

namespace tessera::test {

struct BinMoments {
    int bx = 0, by = 0;
    std::vector<double> sum, sumSq;  ///< per bin and channel, over batches
};

/// Bin means of K renders of `integrator` (seeds 5000 + k), accumulated over the batches.
inline BinMoments renderBinMoments(const Scene& scene, const std::string& integrator, int w, int h, int spp, int batches,
                                   int bin, int maxDepth = -1) {
    BinMoments m;
    m.bx = w / bin;
    m.by = h / bin;
    m.sum.assign(size_t(m.bx * m.by * 3), 0.0);
    m.sumSq.assign(size_t(m.bx * m.by * 3), 0.0);
    std::unique_ptr<Accel> accel = createAccel("embree", scene.geometry);
    std::unique_ptr<Integrator> in = createIntegrator(integrator);
    for (int k = 0; k < batches; ++k) {
        TestRender r = renderScene(scene, *accel, *in, w, h, RenderOptions{.spp = spp, .seed = 5000 + uint64_t(k), .tileSize = 16},
                                   maxDepth);
        EXPECT_EQ(r.stats.nonFiniteDropped, 0u) << integrator;
        for (int j = 0; j < m.by; ++j)
            for (int i = 0; i < m.bx; ++i)
                for (int c = 0; c < 3; ++c) {
                    double v = 0.0;
                    for (int y = j * bin; y < (j + 1) * bin; ++y)
                        for (int x = i * bin; x < (i + 1) * bin; ++x) v += r.film.pixel(x, y)[c];
                    v /= double(bin * bin);
                    size_t idx = size_t((j * m.bx + i) * 3 + c);
                    m.sum[idx] += v;
                    m.sumSq[idx] += v * v;
                }
    }
    return m;
}

/// Every integrator of `runs` (name, spp per batch) agrees with the first one, bin by bin.
inline void expectIntegratorsAgree(const Scene& scene, const std::vector<std::pair<std::string, int>>& runs, int w, int h,
                                   int batches, int bin = 8, double alpha = 0.01, int maxDepth = -1) {
    const double K = batches, nu = K - 1.0;
    BinMoments ref = renderBinMoments(scene, runs[0].first, w, h, runs[0].second, batches, bin, maxDepth);
    for (size_t r = 1; r < runs.size(); ++r) {
        BinMoments m = renderBinMoments(scene, runs[r].first, w, h, runs[r].second, batches, bin, maxDepth);
        const size_t n = m.sum.size();
        double worstZ = 0.0;
        size_t worst = 0;
        int tests = 0;
        for (size_t i = 0; i < n; ++i) {
            double ma = m.sum[i] / K, mb = ref.sum[i] / K;
            double va = std::max(0.0, (m.sumSq[i] - K * ma * ma) / (K - 1.0));
            double vb = std::max(0.0, (ref.sumSq[i] - K * mb * mb) / (K - 1.0));
            double se = std::sqrt(va / K + vb / K);
            if (se == 0.0) {
                EXPECT_NEAR(ma, mb, 1e-6 * std::max(1.0, mb)) << runs[r].first << " vs " << runs[0].first << ": bin " << i / 3;
                continue;
            }
            double t = (ma - mb) / se;
            // Wallace (1959): z ≈ (8ν + 1)/(8ν + 3) · sqrt(ν ln(1 + t²/ν)).
            double z = (8.0 * nu + 1.0) / (8.0 * nu + 3.0) * std::sqrt(nu * std::log1p(t * t / nu));
            ++tests;
            if (z > worstZ) {
                worstZ = z;
                worst = i;
            }
        }
        ASSERT_GT(tests, 0);
        double p = std::erfc(worstZ / std::sqrt(2.0));
        double pSidak = 1.0 - std::pow(1.0 - p, double(tests));
        double ma = m.sum[worst] / K, mb = ref.sum[worst] / K;
        EXPECT_GT(pSidak, alpha) << runs[r].first << " vs " << runs[0].first << ": worst bin " << worst / 3 << " (of "
                                 << m.bx << "x" << m.by << ") channel " << worst % 3 << ": " << ma << " vs " << mb << ", z "
                                 << worstZ << " over " << tests << " tests";
    }
}

}  // namespace tessera::test
