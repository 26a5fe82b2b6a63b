// The sampler (core/sampler.h): net properties of the Sobol' points, scrambled and not; independence
// across seeds, pixels and dimensions; uniformity of higher-dimensional projections; the convergence
// slope it buys on the Cornell box; and determinism of renders with it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <algorithm>
#include <functional>
#include <vector>

#include "chi2_harness.h"
#include "core/sampler.h"
#include "scene/gltf_loader.h"
#include "test_helpers.h"

namespace tessera {
namespace {

/// True when every elementary interval of `dims`-dimensional boxes with 2^a_k cells per axis
/// (Σ a_k = m - t) holds exactly 2^t of the 2^m points (Niederreiter's (t,m,s)-net definition).
/// `bits(i, d)` gives coordinate d of point i as a 32-bit fraction.
bool isNet(int m, int t, int dims, const std::function<uint32_t(uint32_t, int)>& bits, std::string& why) {
    const uint32_t n = 1u << m;
    std::vector<int> a(size_t(dims), 0);
    // Every composition of m - t into `dims` non-negative parts.
    std::function<bool(int, int)> visit = [&](int d, int left) -> bool {
        if (d == dims - 1) {
            a[size_t(d)] = left;
            std::vector<uint32_t> count(size_t(1u << (m - t)), 0);
            for (uint32_t i = 0; i < n; ++i) {
                uint32_t cell = 0;
                for (int k = 0; k < dims; ++k)
                    if (a[size_t(k)] > 0) cell = (cell << a[size_t(k)]) | (bits(i, k) >> (32 - a[size_t(k)]));
                ++count[cell];
            }
            for (uint32_t c : count)
                if (c != (1u << t)) {
                    why = "m=" + std::to_string(m) + " cells";
                    for (int k = 0; k < dims; ++k) why.append(" ").append(std::to_string(a[size_t(k)]));
                    why += ": a cell holds " + std::to_string(c);
                    return false;
                }
            return true;
        }
        for (int v = 0; v <= left; ++v) {
            a[size_t(d)] = v;
            if (!visit(d + 1, left - v)) return false;
        }
        return true;
    };
    return visit(0, m - t);
}

uint32_t floatBits(float u) { return uint32_t(double(u) * 4294967296.0); }

TEST(Sampler, UnscrambledSobolFirstTwoDimensionsAreA02Sequence) {
    std::string why;
    for (int m = 0; m <= 12; ++m)
        for (uint32_t block : {0u, 1u, 5u}) {
            uint32_t base = block << m;  // every aligned block of 2^m points, not only the first
            EXPECT_TRUE(isNet(m, 0, 2, [&](uint32_t i, int d) { return sobolBits(base + i, d); }, why)) << why << " block " << block;
        }
}

TEST(Sampler, UnscrambledSobolFourDimensionsAreANetWithTheSobolTValue) {
    // Sobol's t-value bound Σ (degree - 1) over the four polynomials (1, 1, 2, 3): t = 3. Wrong
    // direction numbers break it for some m.
    std::string why;
    for (int m = 3; m <= 11; ++m)
        EXPECT_TRUE(isNet(m, 3, 4, [&](uint32_t i, int d) { return sobolBits(i, d); }, why)) << why;
    // A single bad column in dimension 3 or 4 is caught.
    for (int m = 3; m <= 11; ++m)
        for (int d = 0; d < kSobolDimensions; ++d)
            EXPECT_TRUE(isNet(m, 0, 1, [&](uint32_t i, int) { return sobolBits(i, d); }, why)) << "dimension " << d << " " << why;
}

TEST(Sampler, ReversedTablesMatchTheMatrices) {
    Pcg32 rng(4, 2);
    for (int i = 0; i < 20000; ++i) {
        uint32_t index = i < 4096 ? uint32_t(i) : rng.nextU32();
        for (int d = 0; d < kSobolDimensions; ++d) ASSERT_EQ(sobolReversedBitsOfReversed(reverseBits32(index), d), reverseBits32(sobolBits(index, d))) << index << " " << d;
    }
    EXPECT_EQ(reverseBits32(1u), 0x80000000u);
    EXPECT_EQ(reverseBits32(0x12345678u), 0x1e6a2c48u);
}

TEST(Sampler, ScrambledDrawsKeepTheNetProperty) {
    // Owen scrambling and the nested-uniform index shuffle preserve the (0,2)-sequence property of
    // every padded 2D draw, and the 4D camera block (jitter, lens) stays a (3,m,4)-net.
    std::string why;
    for (uint64_t seed : {0ull, 77ull})
        for (int m : {0, 1, 4, 7, 10}) {
            const uint32_t n = 1u << m;
            std::vector<Vec2f> jitter(n), lens(n), light(n), bsdf(n), lightPath(n), connect(n);
            for (uint32_t i = 0; i < n; ++i) {
                Sampler s(Vec2i(5, 9), i, seed, SamplerKind::Sobol);
                jitter[i] = s.get2D();
                lens[i] = s.get2D();
                s.startBounce(2);
                (void)s.get1D();
                light[i] = s.get2D();
                (void)s.get1D();
                bsdf[i] = s.get2D();
                s.startLightPath();
                (void)s.get1D();
                lightPath[i] = s.get2D();
                s.startConnection(2, 1);
                connect[i] = s.get2D();
            }
            const char* names[] = {"jitter", "light", "bsdf", "light path", "connection"};
            int k = 0;
            for (auto* pts : {&jitter, &light, &bsdf, &lightPath, &connect})
                EXPECT_TRUE(isNet(m, 0, 2, [&](uint32_t i, int d) { return floatBits((*pts)[i][d]); }, why))
                    << names[k++] << ": " << why << " seed " << seed;
            // The lens is Sobol' dimensions 3-4: not a (0,2) pair, but each axis a (0,1)-sequence.
            for (int d = 0; d < 2; ++d)
                EXPECT_TRUE(isNet(m, 0, 1, [&](uint32_t i, int) { return floatBits(lens[i][d]); }, why)) << "lens " << d << ": " << why;
            if (m >= 3) {
                EXPECT_TRUE(isNet(m, 3, 4, [&](uint32_t i, int d) { return floatBits(d < 2 ? jitter[i][d] : lens[i][d - 2]); }, why))
                    << why << " seed " << seed;
            }
            std::vector<float> rr(n);
            for (uint32_t i = 0; i < n; ++i) {
                Sampler s(Vec2i(5, 9), i, seed, SamplerKind::Sobol);
                s.startBounce(0);
                rr[i] = s.get1D();
            }
            EXPECT_TRUE(isNet(m, 0, 1, [&](uint32_t i, int) { return floatBits(rr[i]); }, why)) << why;
        }
}

double correlation(const std::vector<double>& a, const std::vector<double>& b) {
    double ma = 0, mb = 0;
    for (size_t i = 0; i < a.size(); ++i) ma += a[i], mb += b[i];
    ma /= double(a.size()), mb /= double(b.size());
    double sab = 0, saa = 0, sbb = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        sab += (a[i] - ma) * (b[i] - mb);
        saa += (a[i] - ma) * (a[i] - ma);
        sbb += (b[i] - mb) * (b[i] - mb);
    }
    return sab / std::sqrt(saa * sbb);
}

TEST(Sampler, SeedsPixelsAndDimensionsAreUncorrelated) {
    // Pearson correlation of the same draw under two scramblings: for independent uniform
    // sequences it is ≈ N(0, 1/n); 4.5σ bounds, and the unscrambled (seed-free) Sobol' points would
    // correlate perfectly. Also each draw against the next dimensions of the same sample.
    const int n = 4096;
    const double bound = 4.5 / std::sqrt(double(n));
    struct Key {
        Vec2i pixel;
        uint64_t seed;
    };
    auto draws = [&](Key k, int which) {
        std::vector<double> v(n);
        for (int i = 0; i < n; ++i) {
            Sampler s(k.pixel, uint32_t(i), k.seed, SamplerKind::Sobol);
            Vec2f j = s.get2D();
            if (which == 0) { v[size_t(i)] = j.x; continue; }
            s.startBounce(which == 1 ? 0 : 1);
            (void)s.get1D();
            Vec2f l = s.get2D();
            v[size_t(i)] = which == 3 ? l.y : l.x;
        }
        return v;
    };
    for (int which : {0, 1, 2}) {
        std::vector<double> a = draws({Vec2i(3, 4), 1}, which);
        EXPECT_LT(std::abs(correlation(a, draws({Vec2i(3, 4), 2}, which))), bound) << "seeds, draw " << which;
        EXPECT_LT(std::abs(correlation(a, draws({Vec2i(4, 4), 1}, which))), bound) << "pixels, draw " << which;
        EXPECT_LT(std::abs(correlation(a, draws({Vec2i(3, 5), 1}, which))), bound) << "pixels, draw " << which;
    }
    std::vector<double> jitter = draws({Vec2i(3, 4), 1}, 0);
    EXPECT_LT(std::abs(correlation(jitter, draws({Vec2i(3, 4), 1}, 1))), bound) << "jitter vs bounce 0";
    EXPECT_LT(std::abs(correlation(draws({Vec2i(3, 4), 1}, 1), draws({Vec2i(3, 4), 1}, 2))), bound) << "bounce 0 vs 1";
    EXPECT_LT(std::abs(correlation(draws({Vec2i(3, 4), 1}, 2), draws({Vec2i(3, 4), 1}, 3))), bound) << "x vs y";
}

TEST(Sampler, HigherDimensionalProjectionsAreUniform) {
    // χ² of 4D and 6D projections that combine draws from different blocks (padded Sobol', and the
    // hashed fallback of deep bounces), over 4^4 / 3^6 cells. Pearson's statistic against its
    // upper tail (too uniform is what stratification does; non-uniform is a failure).
    const int n = 1 << 14;
    struct Projection {
        const char* name;
        std::function<std::vector<float>(Sampler&)> draw;
        int binsPerAxis;
    };
    std::vector<Projection> projections = {
        {"jitter x bounce-0 light", [](Sampler& s) {
             Vec2f j = s.get2D();
             s.startBounce(0);
             (void)s.get1D();
             Vec2f l = s.get2D();
             return std::vector<float>{j.x, j.y, l.x, l.y};
         }, 4},
        {"bounce-1 bsdf x bounce-3 light x rr", [](Sampler& s) {
             s.startBounce(1);
             (void)s.get1D(), (void)s.get2D();
             float lobe = s.get1D();
             Vec2f d = s.get2D();
             s.startBounce(3);
             (void)s.get1D();
             Vec2f l = s.get2D();
             s.startBounce(4);
             (void)s.get1D(), (void)s.get2D(), (void)s.get1D(), (void)s.get2D();
             return std::vector<float>{lobe, d.x, d.y, l.x, l.y, s.get1D()};
         }, 3},
        {"fallback: bounce 20 x bounce 21", [](Sampler& s) {
             s.startBounce(20);
             Vec2f a = s.get2D();
             s.startBounce(21);
             Vec2f b = s.get2D();
             return std::vector<float>{a.x, a.y, b.x, b.y};
         }, 4},
        {"light path x connection", [](Sampler& s) {
             s.startLightPath();
             float pick = s.get1D();
             Vec2f pos = s.get2D();
             s.startConnection(1, 3);
             Vec2f c = s.get2D();
             return std::vector<float>{pick, pos.x, pos.y, c.x};
         }, 4},
    };
    for (const Projection& p : projections)
        for (int pixel = 0; pixel < 3; ++pixel) {
            std::vector<double> count;
            for (int i = 0; i < n; ++i) {
                Sampler s(Vec2i(pixel, 7), uint32_t(i), 3, SamplerKind::Sobol);
                std::vector<float> u = p.draw(s);
                if (count.empty()) count.assign(size_t(std::pow(p.binsPerAxis, double(u.size()))), 0.0);
                size_t cell = 0;
                for (float x : u) cell = cell * size_t(p.binsPerAxis) + size_t(x * float(p.binsPerAxis));
                count[cell] += 1.0;
            }
            double expected = double(n) / double(count.size()), chi2 = 0.0;
            for (double c : count) chi2 += (c - expected) * (c - expected) / expected;
            double pValue = test::chi2PValue(chi2, int(count.size()) - 1);
            EXPECT_GT(pValue, 1e-4) << p.name << " pixel " << pixel << " chi2 " << chi2;
        }
}

TEST(Sampler, IndependentKindIsThePcgStreamAndIgnoresBlocks) {
    Sampler a(Vec2i(3, 4), 17, 99, SamplerKind::Independent), b(Vec2i(3, 4), 17, 99, SamplerKind::Independent);
    Pcg32 rng(hashCombine((uint64_t(4) << 32) | 3u, 99), mixBits(17));
    for (int i = 0; i < 20; ++i) {
        a.startBounce(i);
        float x = a.get1D();
        EXPECT_EQ(x, rng.nextFloat());
        EXPECT_EQ(x, b.get1D());
    }
    EXPECT_EQ(parseSamplerKind("sobol"), SamplerKind::Sobol);
    EXPECT_EQ(parseSamplerKind("independent"), SamplerKind::Independent);
    EXPECT_FALSE(parseSamplerKind("halton").has_value());
}

// skip2D (a pinhole camera's lens draw in a lens connection) consumes a draw without computing it:
// every later draw is the one a get2D there would have left, for both kinds.
TEST(Sampler, Skip2DLeavesTheLaterDrawsAsGet2DWould) {
    for (SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Independent}) {
        Sampler a(Vec2i(5, 6), 9, 3, kind), b(Vec2i(5, 6), 9, 3, kind);
        a.startConnection(3, 1);
        b.startConnection(3, 1);
        Vec2f skipped = a.get2D();
        b.skip2D();
        Vec2f x = a.get2D(), y = b.get2D();
        EXPECT_EQ(x, y) << samplerName(kind);
        EXPECT_NE(x, skipped) << samplerName(kind);
        EXPECT_EQ(a.get1D(), b.get1D()) << samplerName(kind);
        a.startBounce(2);
        b.startBounce(2);
        EXPECT_EQ(a.get2D(), b.get2D()) << samplerName(kind);
    }
}

TEST(Sampler, DrawsArePureFunctionsOfPixelIndexSeedAndDimension) {
    // The same key gives the same value whatever was drawn before in other blocks.
    Sampler a(Vec2i(1, 2), 33, 5, SamplerKind::Sobol), b(Vec2i(1, 2), 33, 5, SamplerKind::Sobol);
    (void)a.get2D(), (void)a.get2D();
    a.startBounce(0);
    (void)a.get1D(), (void)a.get2D(), (void)a.get1D();
    a.startBounce(4);
    b.startBounce(4);
    EXPECT_EQ(a.get1D(), b.get1D());
    Vec2f u = a.get2D(), v = b.get2D();
    EXPECT_EQ(u.x, v.x);
    EXPECT_EQ(u.y, v.y);
    // More draws than a block has slots still give fresh numbers, never a repeat of another block.
    Sampler c(Vec2i(1, 2), 33, 5, SamplerKind::Sobol);
    c.startBounce(1);
    std::vector<float> seen;
    for (uint32_t k = 0; k < Sampler::kBlockSlots + 4; ++k) seen.push_back(c.get1D());
    c.startBounce(2);
    for (uint32_t k = 0; k < Sampler::kBlockSlots + 4; ++k) seen.push_back(c.get1D());
    std::sort(seen.begin(), seen.end());
    EXPECT_EQ(std::adjacent_find(seen.begin(), seen.end()), seen.end());
}

/// relMSE of ptnee on the Cornell box at each spp, estimated without a reference: the render is
/// unbiased, so its MSE is its variance, measured across K independent seeds (independent
/// scramblings for sobol). relMSE = mean over pixels and channels of Var / (mean² + 1e-2), leaving
/// out the pixels that see the light (mean > 1): at this resolution each holds a sliver of the
/// emitter, and whether a handful of seeds hit it is a lottery that swamps every other pixel.
std::vector<double> cornellRelMse(SamplerKind kind, const std::vector<int>& spps, int size, int seeds) {
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(test::sourcePath("scenes/cornell-box/cornell-box.gltf"), warnings);
    std::unique_ptr<Accel> accel = createAccel("embree", scene.geometry);
    std::unique_ptr<Integrator> ptnee = createIntegrator("ptnee");
    const size_t values = size_t(size * size * 3);
    std::vector<std::vector<std::vector<double>>> img(spps.size());
    std::vector<double> mean(values, 0.0);
    double weight = 0.0;
    for (size_t k = 0; k < spps.size(); ++k)
        for (int r = 0; r < seeds; ++r) {
            test::TestRender t = test::renderScene(scene, *accel, *ptnee, size, size,
                                                   RenderOptions{.spp = spps[k], .seed = 100 + uint64_t(r) * 7 + k, .sampler = kind});
            std::vector<double> v(values);
            for (int y = 0; y < size; ++y)
                for (int x = 0; x < size; ++x)
                    for (int c = 0; c < 3; ++c) v[size_t((y * size + x) * 3 + c)] = t.film.pixel(x, y)[c];
            for (size_t i = 0; i < values; ++i) mean[i] += double(spps[k]) * v[i];
            weight += double(spps[k]);
            img[k].push_back(std::move(v));
        }
    for (double& m : mean) m /= weight;
    std::vector<double> rel;
    for (size_t k = 0; k < spps.size(); ++k) {
        double sum = 0.0;
        size_t counted = 0;
        for (size_t i = 0; i < values; ++i) {
            if (mean[i] > 1.0) continue;
            ++counted;
            double m = 0.0, s2 = 0.0;
            for (const auto& v : img[k]) m += v[i];
            m /= double(seeds);
            for (const auto& v : img[k]) s2 += (v[i] - m) * (v[i] - m);
            sum += s2 / double(seeds - 1) / (mean[i] * mean[i] + 1e-2);
        }
        rel.push_back(sum / double(counted));
    }
    return rel;
}

double fittedSlope(const std::vector<int>& spps, const std::vector<double>& err) {
    double mx = 0, my = 0;
    for (size_t i = 0; i < spps.size(); ++i) mx += std::log(double(spps[i])), my += std::log(err[i]);
    mx /= double(spps.size()), my /= double(spps.size());
    double sxy = 0, sxx = 0;
    for (size_t i = 0; i < spps.size(); ++i) {
        double dx = std::log(double(spps[i])) - mx;
        sxy += dx * (std::log(err[i]) - my);
        sxx += dx * dx;
    }
    return sxy / sxx;
}

TEST(SamplerConvergence, SobolSlopeOnTheCornellBoxIsSteeperThanIndependent) {
    // ptnee, 16-1024 spp at 16x16 pixels, 6 seeds per spp: the independent sampler's relMSE falls
    // as spp^-1, the scrambled Sobol' sampler's faster (pixel footprint and direct light are smooth).
    const std::vector<int> spps = {16, 64, 256, 1024};
    std::vector<double> sobol = cornellRelMse(SamplerKind::Sobol, spps, 16, 6);
    std::vector<double> independent = cornellRelMse(SamplerKind::Independent, spps, 16, 6);
    // The independent sampler's check fits 64-1024: with 6 seeds its 16-spp variance estimate is
    // low (heavy-tailed pixels), which flattens a 16-1024 fit to about -0.8.
    double slopeSobol = fittedSlope(spps, sobol);
    double slopeIndependent = fittedSlope({spps.begin() + 1, spps.end()}, {independent.begin() + 1, independent.end()});
    std::string table;
    for (size_t i = 0; i < spps.size(); ++i)
        table.append(" ").append(std::to_string(spps[i])).append(": ").append(std::to_string(sobol[i])).append(" / ").append(std::to_string(independent[i]));
    EXPECT_LT(slopeSobol, -1.1) << "relMSE sobol / independent:" << table;
    EXPECT_GT(slopeIndependent, -1.15) << table;
    EXPECT_LT(slopeIndependent, -0.85) << table;
    EXPECT_LT(sobol.back(), independent.back()) << table;
}

TEST(SamplerDeterminism, BothSamplersAreBitIdenticalForOneAndTwoThreads) {
    std::vector<std::string> warnings;
    Scene scene = loadGltfScene(test::sourcePath("scenes/cornell-box/cornell-box.gltf"), warnings);
    std::vector<float> byKind[2];
    for (SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Independent})
        for (const char* name : {"ptnee", "bdpt"}) {
            std::vector<float> images[2];
            for (int threads : {1, 2})
                images[threads - 1] =
                    test::renderScene(scene, name, 40, 32, RenderOptions{.spp = 4, .threads = threads, .seed = 9, .sampler = kind, .tileSize = 16})
                        .film.rgba();
            ASSERT_EQ(images[0].size(), images[1].size());
            EXPECT_EQ(std::memcmp(images[0].data(), images[1].data(), images[0].size() * sizeof(float)), 0)
                << name << " " << samplerName(kind);
            if (std::string(name) == "ptnee") byKind[int(kind)] = images[0];
        }
    EXPECT_NE(std::memcmp(byKind[0].data(), byKind[1].data(), byKind[0].size() * sizeof(float)), 0) << "the kinds differ";
}

}  // namespace
}  // namespace tessera
