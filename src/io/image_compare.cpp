#include "io/image_compare.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "io/image_output.h"

namespace tessera::io {

namespace {

/// Added to ref^2 in the relMSE denominator: black reference pixels would otherwise divide by zero,
/// and near-black ones would dominate the mean.
constexpr double kRelMseEpsilon = 0.01;

bool isFinitePixel(const float* rgba) {
    return std::isfinite(rgba[0]) && std::isfinite(rgba[1]) && std::isfinite(rgba[2]);
}

std::string sizeText(const Image& image) {
    return std::to_string(image.width) + "x" + std::to_string(image.height);
}

/// printf-style formatting into a std::string (GCC 12 has no std::format).
template <typename... Args>
std::string format(const char* pattern, Args... args) {
    char buffer[256];
    std::snprintf(buffer, sizeof(buffer), pattern, args...);
    return buffer;
}

}  // namespace

// Computed in one pass here rather than with OIIO's ImageBufAlgo: computePixelStats counts NaN/Inf
// per channel, not per pixel, and ImageBufAlgo::compare reports an infinite max error for any
// non-finite mismatch instead of skipping the pixel, so neither gives the statistics documented in
// the header. Sums are in double: a 4K image has 25M terms, too many for float accumulation.
CompareResult compareImages(const std::string& testPath, const std::string& refPath) {
    const Image test = readImage(testPath);
    const Image ref = readImage(refPath);
    if (test.width != ref.width || test.height != ref.height) {
        throw InputError(testPath + " is " + sizeText(test) + " but " + refPath + " is " +
                         sizeText(ref) + ": images must have the same resolution");
    }

    CompareResult result;
    result.width = test.width;
    result.height = test.height;

    std::array<double, 3> sumTest{}, sumRef{};
    long finiteTest = 0, finiteRef = 0, compared = 0;
    double sumSquaredError = 0, sumRelativeSquaredError = 0;
    double maxAbsError = -1;
    for (int y = 0; y < test.height; ++y) {
        for (int x = 0; x < test.width; ++x) {
            const std::size_t index = 4 * (std::size_t(y) * test.width + x);
            const float* t = &test.rgba[index];
            const float* r = &ref.rgba[index];
            const bool testOk = isFinitePixel(t), refOk = isFinitePixel(r);
            if (testOk) {
                ++finiteTest;
                for (int c = 0; c < 3; ++c) sumTest[c] += t[c];
            } else {
                ++result.nonFiniteTest;
            }
            if (refOk) {
                ++finiteRef;
                for (int c = 0; c < 3; ++c) sumRef[c] += r[c];
            } else {
                ++result.nonFiniteRef;
            }
            if (!testOk || !refOk) continue;

            ++compared;
            for (int c = 0; c < 3; ++c) {
                const double diff = double(t[c]) - double(r[c]);
                const double squared = diff * diff;
                sumSquaredError += squared;
                sumRelativeSquaredError += squared / (double(r[c]) * r[c] + kRelMseEpsilon);
                if (std::abs(diff) > maxAbsError) {
                    maxAbsError = std::abs(diff);
                    result.maxX = x;
                    result.maxY = y;
                    result.maxChannel = c;
                }
            }
        }
    }

    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    for (int c = 0; c < 3; ++c) {
        result.meanTest[c] = finiteTest > 0 ? sumTest[c] / finiteTest : kNaN;
        result.meanRef[c] = finiteRef > 0 ? sumRef[c] / finiteRef : kNaN;
    }
    if (compared > 0) {
        const double values = 3.0 * compared;
        result.rmse = std::sqrt(sumSquaredError / values);
        result.relMse = sumRelativeSquaredError / values;
        result.maxAbsError = maxAbsError;
    } else {
        result.rmse = result.relMse = result.maxAbsError = kNaN;
    }
    return result;
}

nlohmann::json toJson(const CompareResult& result) {
    // nlohmann writes a NaN double as null, which is what the header promises.
    return nlohmann::json{
        {"width", result.width},
        {"height", result.height},
        {"mean_test", result.meanTest},
        {"mean_ref", result.meanRef},
        {"rmse", result.rmse},
        {"relmse", result.relMse},
        {"max_abs_error",
         {{"value", result.maxAbsError},
          {"x", result.maxX},
          {"y", result.maxY},
          {"channel", result.maxChannel}}},
        {"non_finite_test", result.nonFiniteTest},
        {"non_finite_ref", result.nonFiniteRef},
    };
}

std::string toText(const CompareResult& result) {
    auto mean = [](const std::array<double, 3>& m) {
        return format("%.6g  %.6g  %.6g  (R G B)", m[0], m[1], m[2]);
    };
    const char channelName = result.maxChannel >= 0 ? "RGB"[result.maxChannel] : '?';
    std::string text;
    text += format("%-16s%d x %d\n", "resolution", result.width, result.height);
    text += format("%-16s", "mean test") + mean(result.meanTest) + "\n";
    text += format("%-16s", "mean ref") + mean(result.meanRef) + "\n";
    text += format("%-16s%.6g\n", "RMSE", result.rmse);
    text += format("%-16s%.6g\n", "relMSE", result.relMse);
    text += format("%-16s%.6g at (%d, %d) channel %c\n", "max abs error", result.maxAbsError,
                   result.maxX, result.maxY, channelName);
    text += format("%-16s%ld test, %ld ref (pixels with NaN/Inf, excluded from errors)\n",
                   "non-finite", result.nonFiniteTest, result.nonFiniteRef);
    return text;
}

}  // namespace tessera::io
