#pragma once
/// \file image_compare.h
/// Error metrics between a rendered image and a reference, behind `tessera compare`.
#include <array>
#include <nlohmann/json_fwd.hpp>
#include <string>

namespace tessera::io {

/// Statistics of TEST against REF over the R, G and B channels (alpha is ignored).
///
/// A pixel is non-finite if any of its R, G, B values is NaN or infinite. Non-finite pixels are
/// counted, then excluded: the means skip the image's own non-finite pixels, and the error
/// statistics (rmse, relMse, maxAbsError) use only pixels finite in both images. Excluding them
/// keeps one stray NaN from turning every error into NaN, while the counts still flag it.
/// When no pixel qualifies, the affected values are NaN and the location fields are -1.
struct CompareResult {
    int width = 0, height = 0;
    std::array<double, 3> meanTest{}, meanRef{};  ///< Per channel R, G, B.
    double rmse = 0;         ///< sqrt(mean of (test - ref)^2) over pixels and RGB channels.
    double relMse = 0;       ///< Mean of (test - ref)^2 / (ref^2 + 0.01) over pixels and channels.
    double maxAbsError = 0;  ///< Largest |test - ref| over pixels and channels ...
    int maxX = -1, maxY = -1, maxChannel = -1;  ///< ... and where: column, row (0 = top), 0..2.
    long nonFiniteTest = 0, nonFiniteRef = 0;   ///< Pixel counts, not channel counts.
};

/// Reads both images (any format OIIO reads; see readImage) and compares them.
/// Throws tessera::InputError if either file cannot be read, or if the resolutions differ (the
/// message gives both sizes).
CompareResult compareImages(const std::string& testPath, const std::string& refPath);

/// Machine-readable form, for `tessera compare --json`: keys width, height, mean_test [r,g,b],
/// mean_ref, rmse, relmse, max_abs_error {value, x, y, channel}, non_finite_test,
/// non_finite_ref. NaN values become JSON null.
nlohmann::json toJson(const CompareResult& result);

/// Human-readable form: one aligned "label  value" line per statistic, newline-terminated.
std::string toText(const CompareResult& result);

}  // namespace tessera::io
