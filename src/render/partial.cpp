#include "render/partial.h"

#include <algorithm>
#include <map>

#include "core/error.h"

namespace tessera {
namespace {

std::string valueOf(const CheckpointHeader& h, const std::string& key) {
    auto it = std::find_if(h.begin(), h.end(), [&](const auto& kv) { return kv.first == key; });
    return it == h.end() ? "(absent)" : it->second;
}

bool informational(const std::string& key) {
    const auto& keys = partialInformationalKeys();
    return std::find(keys.begin(), keys.end(), key) != keys.end();
}

/// The first setting (in `a`'s order, then `b`'s) that differs between two partials, or "".
std::string firstDifference(const CheckpointHeader& a, const CheckpointHeader& b) {
    for (const CheckpointHeader* h : {&a, &b})
        for (const auto& [key, value] : *h)
            if (!informational(key) && valueOf(a, key) != valueOf(b, key)) return key;
    return "";
}

struct Part {
    std::string path;
    CheckpointHeader header;
    SampleRange range;
};

std::string listRanges(const std::vector<SampleRange>& ranges) {
    std::string s;
    for (const SampleRange& r : ranges) s += (s.empty() ? "" : ", ") + r.str();
    return s;
}

}  // namespace

SampleRange parseSampleRange(const std::string& text, const std::string& option) {
    auto bad = [&] { return InputError(option + " needs A:B, sample indices with 0 <= A < B <= 2^30, got '" + text + "'"); };
    size_t colon = text.find(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 >= text.size()) throw bad();
    auto number = [&](const std::string& s) {
        if (s.empty() || s.size() > 10 || !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; })) throw bad();
        uint64_t v = std::stoull(s);
        if (v > (uint64_t(1) << 30)) throw bad();
        return uint32_t(v);
    };
    SampleRange r{number(text.substr(0, colon)), number(text.substr(colon + 1))};
    if (r.begin >= r.end) throw bad();
    return r;
}

void writePartial(const std::string& path, const CheckpointHeader& settings, SampleRange range, const Film& film,
                  const RenderStats& stats) {
    CheckpointHeader header = settings;
    header.push_back({"kind", "partial"});
    header.push_back({"samples", range.str()});
    RenderState state;
    state.sppDone = range.end;
    state.passSpp = 1;
    state.samples = stats.samples;
    state.nonFinite = stats.nonFiniteDropped;
    state.seconds = stats.seconds;
    state.firstNonFinite = stats.firstNonFinite;
    writeCheckpoint(path, header, film, state);
}

MergedRender mergePartials(const std::vector<std::string>& paths, bool allowGaps) {
    if (paths.empty()) throw InputError("merge: no partials given");
    // Headers first (cheap): every consistency check before reading any film.
    std::vector<Part> parts;
    for (const std::string& path : paths) {
        Part p{path, readCheckpointHeader(path), {}};
        if (valueOf(p.header, "kind") != "partial")
            throw InputError(path + ": not a partial (a checkpoint of an interrupted render? render with --samples A:B)");
        p.range = parseSampleRange(valueOf(p.header, "samples"), path + ": header 'samples'");
        if (!parts.empty()) {
            std::string key = firstDifference(parts.front().header, p.header);
            if (!key.empty())
                throw InputError("partials from different renders: " + key + " is '" + valueOf(parts.front().header, key) + "' in " +
                                 parts.front().path + ", '" + valueOf(p.header, key) + "' in " + path);
        }
        parts.push_back(std::move(p));
    }
    std::stable_sort(parts.begin(), parts.end(), [](const Part& a, const Part& b) { return a.range.begin < b.range.begin; });

    MergedRender m;
    for (const auto& [key, value] : parts.front().header)
        if (key != "samples" && key != "kind") m.settings.push_back({key, value});
    const std::string target = valueOf(m.settings, "spp_target");
    uint32_t sppTotal = 0;
    try {
        unsigned long n = std::stoul(target);
        if (n == 0 || n > (1ul << 30)) throw std::out_of_range("spp_target");
        sppTotal = uint32_t(n);
    } catch (const std::exception&) {
        throw InputError(parts.front().path + ": partial is corrupt (spp_target '" + target + "')");
    }
    uint32_t covered = 0;
    for (size_t k = 0; k < parts.size(); ++k) {
        const Part& p = parts[k];
        if (p.range.end > sppTotal)
            throw InputError(p.path + ": samples " + p.range.str() + " go past the render's " + target + " spp");
        if (k > 0 && p.range.begin < parts[k - 1].range.end)
            throw InputError("overlapping partials: " + parts[k - 1].path + " (samples " + parts[k - 1].range.str() + ") and " + p.path +
                             " (samples " + p.range.str() + ")");
        if (p.range.begin > covered) m.gaps.push_back({covered, p.range.begin});
        covered = p.range.end;
        m.ranges.push_back(p.range);
    }
    if (covered < sppTotal) m.gaps.push_back({covered, sppTotal});
    if (!m.gaps.empty() && !allowGaps)
        throw InputError("missing samples " + listRanges(m.gaps) + " of 0:" + target + " (render them with --samples, or merge with --allow-gaps)");
    m.sppEnd = sppTotal;

    // Films in the order of their range starts. The sums are exact integers (render/film.h), so
    // this order fixes nothing but the order of the error messages.
    for (const Part& p : parts) {
        CheckpointContents c = readCheckpointContents(p.path);
        if (c.header != p.header) throw InputError(p.path + ": partial changed while merging");
        const uint64_t pixels = uint64_t(c.film->width()) * uint64_t(c.film->height());
        if (valueOf(c.header, "resolution") != std::to_string(c.film->width()) + "x" + std::to_string(c.film->height()) ||
            c.state.sppDone != p.range.end || c.state.samples != pixels * (p.range.end - p.range.begin))
            throw InputError(p.path + ": partial is corrupt (its film does not hold samples " + p.range.str() + " of every pixel)");
        if (m.spp == 0) m.film = Film(c.film->width(), c.film->height());
        m.film.accumulate(*c.film);
        m.spp += p.range.end - p.range.begin;
        m.samples += c.state.samples;
        m.nonFinite += c.state.nonFinite;
        m.seconds += c.state.seconds;
        if (c.state.firstNonFinite && (!m.firstNonFinite || *c.state.firstNonFinite < *m.firstNonFinite))
            m.firstNonFinite = c.state.firstNonFinite;
    }
    // Splats are estimates per camera sample of the whole image: divide by all samples merged, as
    // one render of them would.
    const uint64_t pixels = uint64_t(m.film.width()) * uint64_t(m.film.height());
    m.film.setSplatSppDouble(double(m.samples) / double(pixels));
    return m;
}

}  // namespace tessera
