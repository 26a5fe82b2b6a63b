#pragma once
// Per-pixel Z-test of a render against a reference image and its standard-error image (after
// Mitsuba 3's render tests), made robust for short test renders:
//  * The test render's variance is not estimated from its own few samples (a variance from a
//    handful of samples makes z heavy-tailed). It comes from the reference's standard-error image,
//    which was measured across K independent renders of the *same integrator*: the per-sample
//    variance is σ² = se_ref² · N_ref, so the test's mean of N_test samples has σ² / N_test.
//  * Pixels are averaged in b×b bins first: each bin mean sums b² independent pixel means, so it is
//    much closer to normal than a pixel of a few samples, and its variance estimate has b² times the
//    degrees of freedom of one pixel's.
// Two statistics: the largest |z| over bins and channels, Šidák-corrected over them at level α
// (catches a local error), and the sum of z over all bins / √n (catches a small global bias, e.g.
// an image 5% too dark, that no single bin can see), required below 4 in magnitude: light tracing
// and BDPT splat one light path into several pixels, so bins are slightly positively correlated and
// this sum's spread is a little above 1 (measured: up to 2.4 over 12 seeds of the Cornell box),
// while a 5% bias gives |Σz/√n| ≈ 15 there.
// Bins: 8×8 pixels. With 4×4 bins of a 4-spp BDPT render (64 samples per bin) the Cornell box's
// largest |z| was heavier-tailed than normal (Šidák p < 0.01 in 1 of 12 seeds, < 0.05 in 3); with
// 8×8 bins the 12 seeds gave p-values from 0.06 to 0.84.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace tessera::test {

struct ZTestInput {
    int width = 0, height = 0;
    const float* testRgba = nullptr;    ///< the render under test (packed RGBA)
    const float* refRgba = nullptr;     ///< the reference (mean of the reference renders)
    const float* refSeRgba = nullptr;   ///< standard error of the reference's mean
    double refSamples = 0;              ///< samples per pixel behind the reference (all renders)
    double testSamples = 0;             ///< samples per pixel of the render under test
    int bin = 8;                        ///< bin side in pixels
    double alpha = 0.01;                ///< family-wise level of each of the two statistics
};

struct ZTestResult {
    int tests = 0;             ///< bins × channels with non-zero variance
    double maxAbsZ = 0;        ///< largest |z|, and where:
    int worstX = -1, worstY = -1, worstChannel = -1;  ///< bin corner (pixels), channel
    double worstTest = 0, worstRef = 0, worstSigma = 0;
    double pMinSidak = 1;      ///< the smallest two-sided p-value, Šidák-corrected over all tests
    double globalZ = 0;        ///< Σz / √n
    int zeroVarianceMismatches = 0;  ///< bins whose reference has no variance but whose values differ
    static constexpr double kGlobalZLimit = 4.0;
    bool passed(double alpha) const {
        return pMinSidak > alpha && std::abs(globalZ) < kGlobalZLimit && zeroVarianceMismatches == 0;
    }
    std::string describe() const {
        return "max |z| " + std::to_string(maxAbsZ) + " at bin (" + std::to_string(worstX) + "," + std::to_string(worstY) +
               ") channel " + std::to_string(worstChannel) + ": test " + std::to_string(worstTest) + " ref " +
               std::to_string(worstRef) + " sigma " + std::to_string(worstSigma) + "; Sidak p " +
               std::to_string(pMinSidak) + " over " + std::to_string(tests) + " tests; global z " + std::to_string(globalZ) +
               "; zero-variance mismatches " + std::to_string(zeroVarianceMismatches);
    }
};

inline ZTestResult referenceZTest(const ZTestInput& in) {
    ZTestResult r;
    const int b = in.bin;
    const double ratio = in.refSamples / in.testSamples;  // σ²_test-mean = se_ref² · N_ref / N_test
    double sumZ = 0;
    std::vector<double> z;
    for (int by = 0; by + b <= in.height; by += b)
        for (int bx = 0; bx + b <= in.width; bx += b)
            for (int c = 0; c < 3; ++c) {
                double t = 0, ref = 0, var = 0;
                for (int y = by; y < by + b; ++y)
                    for (int x = bx; x < bx + b; ++x) {
                        size_t i = (size_t(y) * size_t(in.width) + size_t(x)) * 4 + size_t(c);
                        double se = in.refSeRgba[i];
                        double refValue = in.refRgba[i];
                        t += in.testRgba[i];
                        ref += refValue;
                        // The test's variance + the reference's own + the reference's rounding to
                        // half float (uniform within ±2⁻¹¹ relative: variance (2⁻¹¹ |r|)² / 3).
                        double rounding = std::ldexp(std::abs(refValue), -11);
                        var += se * se * (ratio + 1.0) + rounding * rounding / 3.0;
                    }
                double n = double(b) * b;
                t /= n;
                ref /= n;
                double sigma = std::sqrt(var) / n;
                if (!(sigma > 0)) {
                    // Exactly black in every reference render (e.g. the background): the test must be too.
                    if (std::abs(t - ref) > 1e-6) ++r.zeroVarianceMismatches;
                    continue;
                }
                double zi = (t - ref) / sigma;
                z.push_back(zi);
                sumZ += zi;
                if (std::abs(zi) > r.maxAbsZ) {
                    r.maxAbsZ = std::abs(zi);
                    r.worstX = bx;
                    r.worstY = by;
                    r.worstChannel = c;
                    r.worstTest = t;
                    r.worstRef = ref;
                    r.worstSigma = sigma;
                }
            }
    r.tests = int(z.size());
    if (r.tests == 0) return r;
    double pMin = std::erfc(r.maxAbsZ / std::sqrt(2.0));
    // Šidák: P(min p < x) over n independent tests = 1 − (1 − x)ⁿ.
    r.pMinSidak = 1.0 - std::pow(1.0 - pMin, double(r.tests));
    if (pMin < 1e-12) r.pMinSidak = std::min(1.0, pMin * r.tests);  // avoid 1 − (1 − tiny) rounding to 0
    r.globalZ = sumZ / std::sqrt(double(r.tests));
    return r;
}

}  // namespace tessera::test
