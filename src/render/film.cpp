#include "render/film.h"

#include <stdexcept>

namespace tessera {

Film::Film(int width, int height)
    : width_(width), height_(height),
      sum_(size_t(width) * size_t(height) * 3, 0),
      sumSq_(size_t(width) * size_t(height) * 3, 0),
      splat_(size_t(width) * size_t(height) * 3, 0),
      count_(size_t(width) * size_t(height), 0u) {}

void Film::accumulate(const Film& other) {
    if (other.width_ != width_ || other.height_ != height_)
        throw std::invalid_argument("Film::accumulate: films of different sizes");
    for (size_t k = 0; k < sum_.size(); ++k) {
        addFilmAccum(sum_[k], other.sum_[k]);
        addFilmAccum(sumSq_[k], other.sumSq_[k]);
        addFilmAccum(splat_[k], other.splat_[k]);
    }
    for (size_t i = 0; i < count_.size(); ++i) count_[i] += other.count_[i];
}

Rgb Film::pixel(int x, int y) const {
    size_t i = size_t(y) * size_t(width_) + size_t(x);
    Rgb out(0.f);
    for (int c = 0; c < 3; ++c) {
        double v = count_[i] > 0 ? filmAccumValue(sum_[3 * i + c]) / double(count_[i]) : 0.0;
        if (splatSpp_ > 0.0) v += filmAccumValue(splat_[3 * i + c]) / splatSpp_;
        out[c] = float(v);
    }
    return out;
}

Rgb Film::varianceOfMean(int x, int y) const {
    size_t i = size_t(y) * size_t(width_) + size_t(x);
    double n = count_[i];
    Rgb out(0.f);
    if (n < 2) return out;
    for (int c = 0; c < 3; ++c) {
        double mean = filmAccumValue(sum_[3 * i + c]) / n;
        double var = std::max(0.0, (filmAccumValue(sumSq_[3 * i + c]) - n * mean * mean) / (n - 1.0));
        out[c] = float(var / n);
    }
    return out;
}

std::vector<float> Film::rgba() const {
    std::vector<float> out(size_t(width_) * size_t(height_) * 4);
    for (int y = 0; y < height_; ++y)
        for (int x = 0; x < width_; ++x) {
            size_t i = size_t(y) * size_t(width_) + size_t(x);
            Rgb p = pixel(x, y);
            out[4 * i + 0] = p.r;
            out[4 * i + 1] = p.g;
            out[4 * i + 2] = p.b;
            out[4 * i + 3] = count_[i] > 0 ? 1.f : 0.f;
        }
    return out;
}

std::vector<float> Film::standardErrorRgba() const {
    std::vector<float> out(size_t(width_) * size_t(height_) * 4);
    for (int y = 0; y < height_; ++y)
        for (int x = 0; x < width_; ++x) {
            size_t i = size_t(y) * size_t(width_) + size_t(x);
            Rgb v = varianceOfMean(x, y);
            for (int c = 0; c < 3; ++c) out[4 * i + c] = std::sqrt(v[c]);
            out[4 * i + 3] = count_[i] > 0 ? 1.f : 0.f;
        }
    return out;
}

}  // namespace tessera
