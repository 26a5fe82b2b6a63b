#pragma once
/// \file film.h
/// The accumulation buffer. Each pixel keeps the running sum and sum of squares of its own samples
/// (box filter: a sample counts for the pixel it was taken in) and its sample count; a separate
/// splat image collects light-tracing style contributions. Tiles own disjoint pixels, so
/// addSample needs no locking; splats are merged by the scheduler in tile order.
#include <cstdint>
#include <vector>

#include "core/math.h"

namespace tessera {

class Film {
public:
    Film(int width, int height);

    /// Bytes a width x height film takes while rendering and writing out: sum, sum of squares and
    /// splats in double per channel plus a sample count (the accumulation state), and one rgba()
    /// image. Lets a caller refuse a resolution before allocating it.
    static double memoryBytes(int width, int height) {
        return double(width) * double(height) * (9.0 * sizeof(double) + sizeof(uint32_t) + 4 * sizeof(float));
    }

    int width() const { return width_; }
    int height() const { return height_; }

    void addSample(int x, int y, const Rgb& L) {
        size_t i = size_t(y) * size_t(width_) + size_t(x);
        for (int c = 0; c < 3; ++c) {
            sum_[3 * i + c] += double(L[c]);
            sumSq_[3 * i + c] += double(L[c]) * double(L[c]);
        }
        ++count_[i];
    }
    void addSplat(uint32_t pixelIndex, const Rgb& v) {
        for (int c = 0; c < 3; ++c) splat_[3 * size_t(pixelIndex) + c] += double(v[c]);
    }
    /// Number of passes' worth of samples per pixel the splat image holds (divides it).
    void setSplatSppDouble(double spp) { splatSpp_ = spp; }

    uint32_t sampleCount(int x, int y) const { return count_[size_t(y) * size_t(width_) + size_t(x)]; }
    /// Mean of the pixel's samples plus its share of the splats.
    Rgb pixel(int x, int y) const;
    /// Variance of the pixel's mean (sample variance / n), per channel; 0 with fewer than 2 samples.
    Rgb varianceOfMean(int x, int y) const;

    /// Packed float RGBA, row-major from the top row; alpha = 1 where the pixel has samples, else 0.
    std::vector<float> rgba() const;
    /// Packed float RGBA of the per-pixel standard error of the mean (alpha as in rgba()).
    std::vector<float> standardErrorRgba() const;

    /// The raw accumulation state, for checkpoints (render/checkpoint.h): 3 doubles per pixel for
    /// sum, sum of squares and splats, one count per pixel. Restoring these restores the film bit
    /// for bit; the sizes never change.
    std::vector<double>& sumData() { return sum_; }
    std::vector<double>& sumSqData() { return sumSq_; }
    std::vector<double>& splatData() { return splat_; }
    std::vector<uint32_t>& countData() { return count_; }
    const std::vector<double>& sumData() const { return sum_; }
    const std::vector<double>& sumSqData() const { return sumSq_; }
    const std::vector<double>& splatData() const { return splat_; }
    const std::vector<uint32_t>& countData() const { return count_; }

private:
    int width_, height_;
    std::vector<double> sum_, sumSq_, splat_;
    std::vector<uint32_t> count_;
    double splatSpp_ = 0.0;
};

}  // namespace tessera
