#pragma once
// Per-pixel Z-test of a render against a reference image and its standard-error image (after
// Mitsuba 3's render tests), made robust for short test renders:
//  * The test render's variance is not estimated from its own few samples (a variance from a
//    handful of samples makes z heavy-tailed). It comes from the reference's standard-error image,
//    which was measured across K independent renders of the *same integrator*: the per-sample
//    variance is σ² = se_ref² · N_ref, so the test's mean of N_test samples has σ² / N_test. Where
//    the reference combines other methods (refs/README.md), that integrator's own standard-error
//    image (judgedSeRgba) plays this part and refSeRgba is the reference's own noise.
//  * Pixels are averaged in b×b bins first: each bin mean sums b² independent pixel means, so it is
//    much closer to normal than a pixel of a few samples, and its variance estimate has b² times the
//    degrees of freedom of one pixel's.
// Statistics: the largest |z| over bins and channels, Šidák-corrected over them at level α
// (catches a local error); the number of bins with |z| > 3 (catches an error spread over several
// bins); and Σz / √n over all bins (a coarse guard against a global bias), required below 8 in
// magnitude: light tracing and BDPT splat one light path into several pixels, so bins are
// positively correlated and this sum spreads wider than N(0, 1) — over 8 seeds of correct 4-spp
// BDPT renders its standard deviation was ≈ 1 on the Cornell box but ≈ 2 on veach-mis and
// tiny-light (values up to 4.4), while an image 5% too dark gives ≈ −28 on the Cornell box.
// Bins: 8×8 pixels. With 4×4 bins of a 4-spp BDPT render (64 samples per bin) the Cornell box's
// largest |z| was heavier-tailed than normal (Šidák p < 0.01 in 1 of 12 seeds, < 0.05 in 3); with
// 8×8 bins the 12 seeds gave p-values from 0.06 to 0.84.
//
// Fireflies. Where a bin's value comes partly from rare, large samples (caustics reached by BSDF
// sampling, s = 0 strategies), a short render's bin mean is Poisson-like, not normal: one event of
// probability p ≪ 1/N among N samples gives z ≈ 1/√(pN) however right the variance is (measured on
// ring-caustic: |z| up to 8 in 8 seeds of correct 4-spp renders). For such scenes the Šidák bound on
// the largest |z| is not valid and is not applied; a third statistic is, which isolated fireflies
// cannot fail but an error spread over several bins does: the number of bins with |z| > 3 in any
// channel (a white firefly moves all three) must stay within its binomial expectation under
// normality + 4 standard deviations + 2. Those scenes also use 16×16 bins (1024 samples per bin
// at 4 spp), which measured fine on ring-caustic and sphere-cornell-mirror over 8 seeds.
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
    /// Standard error of the mean of refSamples samples per pixel of the integrator under test (its
    /// own renders, measured across K of them): the model of the test render's noise. Null: the
    /// reference itself is that integrator's mean (refSeRgba serves both).
    const float* judgedSeRgba = nullptr;
    double refSamples = 0;              ///< samples per pixel behind judgedSeRgba (all renders)
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
    int bins = 0;              ///< bins with non-zero variance in some channel
    int above3 = 0;            ///< bins with |z| > 3 in some channel
    static constexpr double kGlobalZLimit = 8.0;
    /// Most bins with |z| > 3 that the count test accepts: binomial mean + 4 sd + 2, with the
    /// per-bin probability 1 − (1 − p)³ of three independent channels (an upper bound when they
    /// are positively correlated).
    int above3Limit() const {
        double p1 = std::erfc(3.0 / std::sqrt(2.0)), p = 1.0 - std::pow(1.0 - p1, 3.0), mean = p * bins;
        return int(mean + 4.0 * std::sqrt(mean * (1 - p)) + 2.0);
    }
    /// `sidak`: also apply the Šidák bound to the largest |z| (valid where bins are near normal).
    bool passed(double alpha, bool sidak = true) const {
        return (!sidak || pMinSidak > alpha) && std::abs(globalZ) < kGlobalZLimit && above3 <= above3Limit() &&
               zeroVarianceMismatches == 0;
    }
    std::string describe() const {
        return "max |z| " + std::to_string(maxAbsZ) + " at bin (" + std::to_string(worstX) + "," + std::to_string(worstY) +
               ") channel " + std::to_string(worstChannel) + ": test " + std::to_string(worstTest) + " ref " +
               std::to_string(worstRef) + " sigma " + std::to_string(worstSigma) + "; Sidak p " +
               std::to_string(pMinSidak) + " over " + std::to_string(tests) + " tests; global z " + std::to_string(globalZ) +
               "; |z| > 3 in " + std::to_string(above3) + " (limit " + std::to_string(above3Limit()) + ")" +
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
        for (int bx = 0; bx + b <= in.width; bx += b) {
            bool binCounted = false, binAbove3 = false;
            for (int c = 0; c < 3; ++c) {
                double t = 0, ref = 0, var = 0;
                for (int y = by; y < by + b; ++y)
                    for (int x = bx; x < bx + b; ++x) {
                        size_t i = (size_t(y) * size_t(in.width) + size_t(x)) * 4 + size_t(c);
                        double se = in.refSeRgba[i];
                        double seJudged = in.judgedSeRgba ? in.judgedSeRgba[i] : se;
                        double refValue = in.refRgba[i];
                        t += in.testRgba[i];
                        ref += refValue;
                        // The test's variance + the reference's own + the reference's rounding to
                        // half float (uniform within ±2⁻¹¹ relative: variance (2⁻¹¹ |r|)² / 3).
                        double rounding = std::ldexp(std::abs(refValue), -11);
                        var += seJudged * seJudged * ratio + se * se + rounding * rounding / 3.0;
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
                binCounted = true;
                binAbove3 = binAbove3 || std::abs(zi) > 3.0;
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
            r.bins += binCounted ? 1 : 0;
            r.above3 += binAbove3 ? 1 : 0;
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
