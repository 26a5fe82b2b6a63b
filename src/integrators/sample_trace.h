#pragma once
/// \file sample_trace.h
/// What one camera sample did inside the integrator, for `render --debug-pixel x,y,s`
/// (render/debug_pixel.cpp): per path vertex its position, throughput, the densities of the
/// directions sampled there (BSDF pdfW, light pdfW, sub-path pdfFwdA/pdfRevA), MIS weights and
/// contributions; per BDPT strategy (s,t) its unweighted contribution and weight. Integrators
/// record only when RenderContext::trace is set, which only the replay does: in a render every
/// hook is one never-taken branch on a pointer (`if (ctx.trace) [[unlikely]]`), and a hook only
/// reads values the integrator computed anyway (or recomputes a density without drawing random
/// numbers), so traced and untraced samples give the same bits.
#include <cstdint>
#include <iosfwd>
#include <span>
#include <string>
#include <vector>

#include "core/math.h"

namespace tessera {

struct PathVertex;

class SampleTrace {
public:
    struct Field {
        const char* name;  ///< a string literal, e.g. "pdfW"
        uint8_t dims;      ///< 1 (scalar) or 3 (point, direction, colour)
        float v[3];
    };
    /// One line of the trace: "<kind> <index>" (index2 ≥ 0: "<kind> s=<index> t=<index2>").
    struct Record {
        const char* kind;
        int index = 0, index2 = -1;
        uint64_t afterRays = 0;  ///< rays cast when the record began (matches the ray numbers)
        std::vector<Field> fields;
    };

    /// Starts a record; the following add() calls fill it.
    void begin(const char* kind, int index, int index2 = -1) { records_.push_back({kind, index, index2, rays, {}}); }
    void add(const char* name, float v) { push({name, 1, {v, 0.f, 0.f}}); }
    /// Points, directions and colours (Rgb is the same glm type as Vec3f).
    void add(const char* name, const Vec3f& v) { push({name, 3, {v.x, v.y, v.z}}); }
    /// The record of a path vertex as the path tracers write it (position, geometric normal,
    /// material, throughput so far), and the BSDF sample taken there.
    void vertex(int depth, const Vec3f& p, const Vec3f& ng, uint32_t materialId, const Vec3f& beta) {
        begin("vertex", depth);
        add("p", p);
        add("ng", ng);
        add("material", float(materialId));
        add("beta", beta);
    }
    void bsdfSample(const Vec3f& wi, float pdfW, bool isDelta, const Vec3f& weight) {
        add("bsdfWi", wi);
        add("bsdfPdfW", pdfW);
        add("bsdfDelta", isDelta ? 1.f : 0.f);
        add("bsdfWeight", weight);
    }
    /// Remembers `where` as the first non-finite value unless one was seen already.
    void noteNonFinite(const std::string& where) {
        if (firstNonFinite_.empty()) firstNonFinite_ = where;
    }

    const std::vector<Record>& records() const { return records_; }
    const std::string& firstNonFinite() const { return firstNonFinite_; }
    /// One line per record: "  <kind> <index> (after ray N): name=value ...".
    void print(std::ostream& out) const;

    uint64_t rays = 0;  ///< rays cast so far: kept by the replay's tracing accelerator

private:
    void push(const Field& f);
    std::vector<Record> records_;
    std::string firstNonFinite_;
};

/// One record per sub-path vertex (lt, bdpt): kind "camera vertex" or "light vertex", with its
/// position, normal, throughput beta, pdfFwdA, pdfRevA and whether it scattered by a delta lobe.
void traceSubpath(SampleTrace& trace, const char* kind, std::span<const PathVertex> vertices);

/// "camera vertex 2: pdfFwdA" — names a field for noteNonFinite.
std::string describeField(const SampleTrace::Record& r, const char* field);

}  // namespace tessera
