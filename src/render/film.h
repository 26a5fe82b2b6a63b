#pragma once
/// \file film.h
/// The accumulation buffer. Each pixel keeps the running sum and sum of squares of its own samples
/// (box filter: a sample counts for the pixel it was taken in) and its sample count; a separate
/// splat image collects light-tracing style contributions. Tiles own disjoint pixels, so
/// addSample needs no locking; splats are merged by the scheduler in tile order.
///
/// The sums are exact and order-independent: every contribution is rounded once, on its own, to a
/// signed 128-bit fixed-point number with 64 fraction bits (a multiple of 2^-64 ~ 5.4e-20, at most
/// 2^62 ~ 4.6e18 in magnitude), and integer addition is associative. A pixel's sums are right while
/// they stay below 2^63 ~ 9.2e18 (for the sum of squares: samples below ~3e9). So a film holding samples
/// [0, N) has the same bits however those samples were grouped, ordered or split across processes:
/// `render --samples A:B` partials merged by `tessera merge` equal a single render bit for bit
/// (writeup, "Farm rendering"). Floating-point sums would differ in the last bits with the grouping.
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/math.h"

namespace tessera {

/// One exact accumulator: a value v is held as round-toward-zero(v * 2^64) (see above).
__extension__ typedef __int128 FilmAccum;

/// a += b modulo 2^128 (unsigned arithmetic: wrapping is defined, and addition modulo 2^128 is
/// still associative, so the order-independence holds even past the range).
inline void addFilmAccum(FilmAccum& a, FilmAccum b) {
    __extension__ typedef unsigned __int128 U;
    a = FilmAccum(U(a) + U(b));
}
/// v as a FilmAccum: truncated to a multiple of 2^-64, saturated at +-2^62. Equal to
/// FilmAccum(v * 2^64) bit for bit, without libgcc's generic __fixdfti (a call and ~40
/// instructions, nine per camera sample): the magnitude is cut into 64 + 32 + 32 bits by three
/// hardware truncations, each remainder exact (it keeps only bits the double already has).
inline FilmAccum toFilmAccum(double v) {
    double scaled = v * 0x1p64;
    double mag = std::fabs(scaled);
    if (!(mag < 0x1p126)) return scaled > 0 ? FilmAccum(1) << 126 : -(FilmAccum(1) << 126);
    __extension__ typedef unsigned __int128 U;
    uint64_t hi = uint64_t(int64_t(mag * 0x1p-64));    // < 2^62, at most 53 significant bits
    double rem = mag - double(hi) * 0x1p64;            // [0, 2^64), exact
    uint64_t mid = uint64_t(int64_t(rem * 0x1p-32));   // < 2^32
    uint64_t lo = uint64_t(int64_t(rem - double(mid) * 0x1p32));  // [0, 2^32), exact
    U u = (U(hi) << 64) | (mid << 32) | lo;
    return scaled < 0 ? -FilmAccum(u) : FilmAccum(u);
}
/// The accumulator's value, rounded to the nearest double.
inline double filmAccumValue(FilmAccum a) { return double(a) * 0x1p-64; }

class Film {
public:
    Film(int width, int height);

    /// Bytes a width x height film takes while rendering and writing out: sum, sum of squares and
    /// splats as a FilmAccum per channel plus a sample count (the accumulation state), and one rgba()
    /// image. Lets a caller refuse a resolution before allocating it.
    static double memoryBytes(int width, int height) {
        return double(width) * double(height) * (9.0 * sizeof(FilmAccum) + sizeof(uint32_t) + 4 * sizeof(float));
    }

    int width() const { return width_; }
    int height() const { return height_; }

    void addSample(int x, int y, const Rgb& L) {
        size_t i = size_t(y) * size_t(width_) + size_t(x);
        for (int c = 0; c < 3; ++c) {
            // A float's square is exact in double (24 + 24 significant bits).
            addFilmAccum(sum_[3 * i + c], toFilmAccum(double(L[c])));
            addFilmAccum(sumSq_[3 * i + c], toFilmAccum(double(L[c]) * double(L[c])));
        }
        ++count_[i];
    }
    void addSplat(uint32_t pixelIndex, const Rgb& v) {
        for (int c = 0; c < 3; ++c) addFilmAccum(splat_[3 * size_t(pixelIndex) + c], toFilmAccum(double(v[c])));
    }
    /// Number of passes' worth of samples per pixel the splat image holds (divides it).
    void setSplatSppDouble(double spp) { splatSpp_ = spp; }
    double splatSpp() const { return splatSpp_; }
    /// Adds another film's accumulation state (same size) to this one: the film that holds both
    /// films' samples, bit for bit (see above). The splat divisor is left to the caller.
    void accumulate(const Film& other);

    uint32_t sampleCount(int x, int y) const { return count_[size_t(y) * size_t(width_) + size_t(x)]; }
    /// Mean of the pixel's samples plus its share of the splats.
    Rgb pixel(int x, int y) const;
    /// Variance of the pixel's mean (sample variance / n), per channel; 0 with fewer than 2 samples.
    Rgb varianceOfMean(int x, int y) const;

    /// Packed float RGBA, row-major from the top row; alpha = 1 where the pixel has samples, else 0.
    std::vector<float> rgba() const;
    /// Packed float RGBA of the per-pixel standard error of the mean (alpha as in rgba()).
    std::vector<float> standardErrorRgba() const;

    /// The raw accumulation state, for checkpoints and partials (render/checkpoint.h): 3
    /// accumulators per pixel for sum, sum of squares and splats, one count per pixel. Restoring
    /// these restores the film bit for bit; the sizes never change.
    std::vector<FilmAccum>& sumData() { return sum_; }
    std::vector<FilmAccum>& sumSqData() { return sumSq_; }
    std::vector<FilmAccum>& splatData() { return splat_; }
    std::vector<uint32_t>& countData() { return count_; }
    const std::vector<FilmAccum>& sumData() const { return sum_; }
    const std::vector<FilmAccum>& sumSqData() const { return sumSq_; }
    const std::vector<FilmAccum>& splatData() const { return splat_; }
    const std::vector<uint32_t>& countData() const { return count_; }

private:
    int width_, height_;
    std::vector<FilmAccum> sum_, sumSq_, splat_;
    std::vector<uint32_t> count_;
    double splatSpp_ = 0.0;
};

}  // namespace tessera
