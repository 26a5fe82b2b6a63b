// Sample-range partials and `tessera merge`: any split of 0:N, merged from the part files in any
// order, gives the bits of one render of N spp for every integrator; every malformed merge is
// refused with a one-line message and exit 2 (overlaps, gaps, other settings, corrupt or truncated
// files), never a crash; --allow-gaps records what is missing. And the film's exact sums, which
// make that possible, do not depend on how the samples are grouped.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstring>
#include <fstream>
#include <map>
#include <random>

#include "core/error.h"
#include "io/image_output.h"
#include "render/partial.h"
#include "cli_run.h"
#include "test_helpers.h"

namespace {

namespace fs = std::filesystem;

using tessera::test::CliRun;

CliRun tessera(const fs::path& dir, const std::string& args) { return tessera::test::runTessera(dir, args); }

std::string scene(const std::string& name = "cornell-box") {
    return "'" + tessera::test::sourcePath("scenes/" + name + "/" + name + ".gltf") + "'";
}

/// The settings every render of a test shares (16 spp in all).
std::string common(const std::string& integrator, int seed = 3) {
    return " --quiet --no-png --resolution 40x30 --spp 16 --max-depth 4 --seed " + std::to_string(seed) + " --integrator " + integrator;
}

fs::path renderPart(const fs::path& dir, const std::string& integrator, const std::string& range, int seed = 3,
                    const std::string& sceneName = "cornell-box") {
    std::string name = range;
    std::replace(name.begin(), name.end(), ':', '-');
    fs::path out = dir / (integrator + "_" + std::to_string(seed) + "_" + sceneName + "_" + name + ".partial");
    CliRun r = tessera(dir, "render " + scene(sceneName) + common(integrator, seed) + " --samples " + range + " -o '" + out.string() + "'");
    EXPECT_EQ(r.code, 0) << r.err;
    return out;
}

void expectSameBits(const fs::path& a, const fs::path& b) {
    tessera::test::expectSameBitsAndProvenance(a, b,
                                               {"tessera:spp", "tessera:samples", "tessera:seed", "tessera:integrator",
                                                "tessera:resolution", "tessera:scene_hash", "tessera:max_depth",
                                                "tessera:nonfinite_dropped"});
}

/// Parts 0:1, 1:7 and 7:16 (uneven, the first a single sample), merged from the command line in
/// two different orders, against one render of 16 spp.
void expectMergeIsBitIdentical(const std::string& integrator) {
    fs::path dir = tessera::test::tempDir("merge-" + integrator);
    fs::path full = dir / "full.exr";
    CliRun r = tessera(dir, "render " + scene() + common(integrator) + " --threads 2 -o '" + full.string() + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    fs::path a = renderPart(dir, integrator, "0:1"), b = renderPart(dir, integrator, "1:7"), c = renderPart(dir, integrator, "7:16");
    for (const std::string& order : {"'" + c.string() + "' '" + a.string() + "' '" + b.string() + "'",
                                     "'" + b.string() + "' '" + c.string() + "' '" + a.string() + "'"}) {
        fs::path merged = dir / "merged.exr";
        fs::path se = dir / "merged_stderr.exr";
        r = tessera(dir, "merge " + order + " --quiet --no-png -o '" + merged.string() + "' --stderr-image '" + se.string() + "'");
        ASSERT_EQ(r.code, 0) << r.err;
        expectSameBits(merged, full);
        tessera::io::Image s = tessera::io::readImage(se.string());
        double seSum = 0;
        for (float v : s.rgba) seSum += v;
        EXPECT_GT(seSum, 0.0) << "standard-error image is empty";
    }
}

TEST(Merge, PtSplitsAreBitIdentical) { expectMergeIsBitIdentical("pt"); }
TEST(Merge, PtneeSplitsAreBitIdentical) { expectMergeIsBitIdentical("ptnee"); }
TEST(Merge, LtSplitsAreBitIdentical) { expectMergeIsBitIdentical("lt"); }
TEST(Merge, BdptSplitsAreBitIdentical) { expectMergeIsBitIdentical("bdpt"); }
// One photon map per sample index (integrators/sppm.h): parts prepare the same maps as the full render.
TEST(Merge, SppmSplitsAreBitIdentical) { expectMergeIsBitIdentical("sppm"); }
TEST(Merge, VcmSplitsAreBitIdentical) { expectMergeIsBitIdentical("vcm"); }

/// Runs a merge expected to fail: exit 2, one line on stderr, which contains every `needles`.
void expectRefused(const fs::path& dir, const std::string& parts, const std::vector<std::string>& needles) {
    CliRun r = tessera(dir, "merge " + parts + " --quiet --no-png -o '" + (dir / "refused.exr").string() + "'");
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(r.err.rfind("tessera: error: ", 0), 0u) << r.err;
    for (const std::string& n : needles) EXPECT_NE(r.err.find(n), std::string::npos) << "'" << n << "' not in: " << r.err;
    EXPECT_FALSE(fs::exists(dir / "refused.exr"));
}

std::string q(const fs::path& p) { return "'" + p.string() + "' "; }

TEST(Merge, RefusesOverlapsAndGaps) {
    fs::path dir = tessera::test::tempDir("merge-refusals");
    fs::path a = renderPart(dir, "ptnee", "0:8"), b = renderPart(dir, "ptnee", "8:16"), overlap = renderPart(dir, "ptnee", "6:9");
    fs::path c = renderPart(dir, "ptnee", "12:16");
    ASSERT_EQ(tessera(dir, "merge " + q(a) + q(b) + "--quiet --no-png -o " + q(dir / "ok.exr")).code, 0);
    expectRefused(dir, q(a) + q(overlap) + q(b), {"overlapping partials", "0:8", "6:9", a.filename().string(), overlap.filename().string()});
    expectRefused(dir, q(a) + q(a) + q(b), {"overlapping partials", "0:8"});
    expectRefused(dir, q(c) + q(a), {"missing samples 8:12", "--allow-gaps"});
    expectRefused(dir, q(b), {"missing samples 0:8"});
}

TEST(Merge, RefusesOtherSettingsAndCorruptFiles) {
    fs::path dir = tessera::test::tempDir("merge-refusals-settings");
    fs::path a = renderPart(dir, "ptnee", "0:8"), b = renderPart(dir, "ptnee", "8:16");
    expectRefused(dir, q(a) + q(renderPart(dir, "ptnee", "8:16", 4)), {"different renders", "seed", "'3'", "'4'"});
    expectRefused(dir, q(a) + q(renderPart(dir, "pt", "8:16")), {"different renders", "integrator", "'ptnee'", "'pt'"});
    expectRefused(dir, q(a) + q(renderPart(dir, "ptnee", "8:16", 3, "cornell-box-specular")), {"different renders", "scene_hash"});
    // sppm's photon settings are part of what a render is.
    fs::path photonsA = renderPart(dir, "sppm", "0:8"), photonsB = dir / "sppm-alpha.partial";
    ASSERT_EQ(tessera(dir, "render " + scene() + common("sppm") + " --alpha 0.5 --samples 8:16 -o " + q(photonsB)).code, 0);
    expectRefused(dir, q(photonsA) + q(photonsB), {"different renders", "photon_alpha"});
    expectRefused(dir, q(a) + q(dir / "absent.partial"), {"absent.partial"});

    // A flipped byte in the film: the checksum names it.
    fs::path corrupt = dir / "corrupt.partial";
    fs::copy_file(b, corrupt);
    {
        std::fstream f(corrupt, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(std::streamoff(fs::file_size(corrupt) / 2));
        char ch = 0x5a;
        f.write(&ch, 1);
    }
    expectRefused(dir, q(a) + q(corrupt), {"corrupt.partial", "corrupt (CRC-32 mismatch)"});
    // An image is not a partial.
    fs::path exr = dir / "image.exr";
    ASSERT_EQ(tessera(dir, "render " + scene() + common("ptnee") + " -o '" + exr.string() + "'").code, 0);
    expectRefused(dir, q(a) + q(exr), {"image.exr", "not a Tessera checkpoint or partial"});
}

TEST(Merge, AllowGapsRecordsTheMissingRanges) {
    fs::path dir = tessera::test::tempDir("merge-gaps");
    fs::path a = renderPart(dir, "bdpt", "0:1"), c = renderPart(dir, "bdpt", "7:12");
    fs::path out = dir / "gaps.exr";
    CliRun r = tessera(dir, "merge " + q(c) + q(a) + "--allow-gaps --no-png -o " + q(out));
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("missing samples 1:7,12:16"), std::string::npos) << r.err;
    auto md = tessera::test::imageMetadata(tessera::io::readImage(out.string()));
    EXPECT_EQ(md["tessera:missing_samples"], "1:7,12:16");
    EXPECT_EQ(md["tessera:merged_samples"], "0:1,7:12");
    EXPECT_EQ(md["tessera:spp"], "6");
    EXPECT_EQ(md["tessera:samples"], std::to_string(40 * 30 * 6));
    // The same two ranges in one process, with no gap flag, would be refused.
    expectRefused(dir, q(a) + q(c), {"missing samples 1:7, 12:16"});
}

/// Every prefix of a partial that ends on a 4 KiB boundary (and the ones a byte short of the end)
/// is refused with InputError by the reader the merge uses; none crashes.
TEST(Merge, TruncatedPartialsAreRefusedAtEvery4KiBBoundary) {
    fs::path dir = tessera::test::tempDir("merge-truncated");
    fs::path a = renderPart(dir, "bdpt", "0:2");
    std::ifstream in(a, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 3 * 4096u);
    std::vector<size_t> cuts;
    for (size_t n = 0; n < bytes.size(); n += 4096) cuts.push_back(n);
    for (size_t n : {size_t(1), size_t(8), size_t(20), bytes.size() - 4, bytes.size() - 1}) cuts.push_back(n);
    fs::path cut = dir / "cut.partial";
    for (size_t n : cuts) {
        {
            std::ofstream out(cut, std::ios::binary | std::ios::trunc);
            out.write(bytes.data(), std::streamsize(n));
        }
        EXPECT_THROW(tessera::mergePartials({cut.string()}, true), tessera::InputError) << "prefix of " << n << " bytes";
    }
    // The untruncated file merges; the command line refuses one cut with exit 2.
    EXPECT_NO_THROW(tessera::mergePartials({a.string()}, true));
    {
        std::ofstream out(cut, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), std::streamsize(bytes.size() / 2 / 4096 * 4096));
    }
    expectRefused(dir, q(cut) + "--allow-gaps", {"cut.partial", "truncated"});
}

/// The film's sums are the same bits however the contributions are grouped: values over 40 orders
/// of magnitude (1e-20 to 1e20: the largest saturate and their sums wrap, and stay order-independent),
/// added one by one into one film, or in reverse order into three films added together.
TEST(Merge, FilmSumsDoNotDependOnGrouping) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> exponent(-20.f, 20.f), unit(0.f, 1.f);
    std::vector<tessera::Rgb> samples;
    for (int k = 0; k < 3000; ++k)
        samples.push_back(tessera::Rgb(std::pow(10.f, exponent(rng)), unit(rng) * 1e-3f, std::pow(2.f, exponent(rng))));
    tessera::Film one(2, 1), parts[3] = {tessera::Film(2, 1), tessera::Film(2, 1), tessera::Film(2, 1)};
    for (size_t k = 0; k < samples.size(); ++k) {
        one.addSample(int(k % 2), 0, samples[k]);
        one.addSplat(uint32_t(k % 2), samples[k]);
    }
    // Reverse order, uneven split.
    for (size_t k = samples.size(); k-- > 0;) {
        tessera::Film& f = parts[k < 7 ? 0 : k < 1500 ? 1 : 2];
        f.addSample(int(k % 2), 0, samples[k]);
        f.addSplat(uint32_t(k % 2), samples[k]);
    }
    tessera::Film merged(2, 1);
    for (const tessera::Film& f : parts) merged.accumulate(f);
    EXPECT_TRUE(merged.sumData() == one.sumData());
    EXPECT_TRUE(merged.sumSqData() == one.sumSqData());
    EXPECT_TRUE(merged.splatData() == one.splatData());
    EXPECT_EQ(merged.countData(), one.countData());
    one.setSplatSppDouble(1500);
    merged.setSplatSppDouble(1500);
    EXPECT_EQ(std::memcmp(one.rgba().data(), merged.rgba().data(), 8 * sizeof(float)), 0);
    // And the value is right: the exact sum of 3000 values, to double rounding of the result.
    double expect = 0;
    for (size_t k = 0; k < samples.size(); k += 2) expect += double(samples[k].g);
    EXPECT_NEAR(tessera::filmAccumValue(one.sumData()[1]), expect, 1e-12 * expect);
}

/// toFilmAccum's three-part truncation equals the compiler's double -> __int128 conversion (libgcc's
/// __fixdfti) on every magnitude the film holds: doubles with random 53-bit significands at
/// exponents from 2^-90 to just below the saturation at 2^62, both signs, and the edges.
TEST(Merge, FilmAccumConversionIsExactTruncation) {
    std::mt19937_64 rng(29);
    std::vector<double> values = {0.0, -0.0, 0x1p-64, 0x1p-65, 0x1p-1, 1.0, 0x1p62 - 0x1p9, std::nextafter(0x1p62, 0.0), 0x1p31,
                                  0x1p32, 0x1p63 * 0x1p-64, 1.0 - 0x1p-53, 0x1.fffffffffffffp-1, 3.0 * 0x1p-33};
    for (int k = 0; k < 200000; ++k) {
        double significand = 1.0 + double(rng() >> 11) * 0x1p-53;  // [1, 2), all 53 bits random
        int exponent = int(rng() % 152) - 90;                        // 2^-90 .. 2^61
        values.push_back(std::ldexp(significand, exponent));
    }
    for (double v : values)
        for (double x : {v, -v}) {
            __extension__ typedef __int128 I;
            I expect = I(x * 0x1p64);
            ASSERT_TRUE(tessera::toFilmAccum(x) == expect) << std::hexfloat << x;
        }
    // Beyond 2^62 the accumulator saturates; NaN goes to the negative end (as before the fast path).
    EXPECT_TRUE(tessera::toFilmAccum(0x1p62) == tessera::FilmAccum(1) << 126);
    EXPECT_TRUE(tessera::toFilmAccum(-1e30) == -(tessera::FilmAccum(1) << 126));
    EXPECT_TRUE(tessera::toFilmAccum(std::nan("")) == -(tessera::FilmAccum(1) << 126));
}

TEST(Merge, SampleRangeOptionIsChecked) {
    fs::path dir = tessera::test::tempDir("merge-options");
    for (const char* bad : {"8:4", "3:3", "-1:4", "a:b", "4", "0:17"}) {
        CliRun r = tessera(dir, "render " + scene() + common("ptnee") + " --samples " + bad + " -o '" + (dir / "x.partial").string() + "'");
        EXPECT_EQ(r.code, 2) << bad << ": " << r.err;
        EXPECT_NE(r.err.find("--samples"), std::string::npos) << r.err;
    }
}

}  // namespace
