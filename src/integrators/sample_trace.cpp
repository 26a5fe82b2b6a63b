#include "integrators/sample_trace.h"

#include <cmath>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "integrators/path_vertex.h"

namespace tessera {

std::string describeField(const SampleTrace::Record& r, const char* field) {
    std::ostringstream s;
    s << r.kind << " ";
    if (r.index2 >= 0) s << "s=" << r.index << " t=" << r.index2;
    else s << r.index;
    s << ": " << field;
    return s.str();
}

void traceSubpath(SampleTrace& trace, const char* kind, std::span<const PathVertex> vertices) {
    for (size_t i = 0; i < vertices.size(); ++i) {
        const PathVertex& v = vertices[i];
        trace.begin(kind, int(i));
        trace.add("type", float(int(v.type)));
        trace.add("p", v.p);
        trace.add("ng", v.ng);
        trace.add("beta", v.beta);
        trace.add("pdfFwdA", v.pdfFwdA);
        trace.add("pdfRevA", v.pdfRevA);
        trace.add("delta", v.delta ? 1.f : 0.f);
    }
}

void SampleTrace::push(const Field& f) {
    if (records_.empty()) begin("sample", 0);
    Record& r = records_.back();
    r.fields.push_back(f);
    for (int c = 0; c < f.dims; ++c)
        if (!std::isfinite(f.v[c])) {
            noteNonFinite(describeField(r, f.name));
            break;
        }
}

void SampleTrace::print(std::ostream& out) const {
    std::ostringstream s;
    s << std::setprecision(7);
    for (const Record& r : records_) {
        s << "  " << r.kind << " ";
        if (r.index2 >= 0) s << "s=" << r.index << " t=" << r.index2;
        else s << r.index;
        s << " (after ray " << r.afterRays << "):";
        for (const Field& f : r.fields) {
            s << " " << f.name << "=";
            if (f.dims == 1) s << f.v[0];
            else s << "(" << f.v[0] << ", " << f.v[1] << ", " << f.v[2] << ")";
        }
        s << "\n";
    }
    out << s.str();
}

}  // namespace tessera
