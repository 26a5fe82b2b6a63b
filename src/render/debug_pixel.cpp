#include "render/debug_pixel.h"

#include <iomanip>
#include <ostream>
#include <sstream>

#include "core/fp_env.h"
#include "core/thread_pool.h"
#include "integrators/sample_trace.h"

namespace tessera {
namespace {

std::string fmt(const Vec3f& v) {
    std::ostringstream s;
    s << std::setprecision(9) << "(" << v.x << ", " << v.y << ", " << v.z << ")";
    return s.str();
}

/// An Accel that forwards to another and writes every query and its answer to the trace. The
/// integrator only sees rays through the Accel interface, so this shows every ray and shadow test;
/// what the integrator computes between rays (pdfs, MIS weights, throughput) it records in the
/// SampleTrace, which also keeps the ray count and the first non-finite value in event order.
/// Used for one sample, never in a render.
class TracingAccel : public Accel {
public:
    TracingAccel(const Accel& inner, const Scene& scene, std::ostream& trace, SampleTrace& record)
        : inner_(inner), scene_(scene), out_(trace), record_(record) {}
    std::string_view name() const override { return inner_.name(); }
    Bounds3f bounds() const override { return inner_.bounds(); }
    AccelStats stats() const override { return inner_.stats(); }

    bool intersect(const Ray& ray, Hit& hit) const override {
        uint64_t k = ++record_.rays;
        noteNonFinite(ray, k);
        bool found = inner_.intersect(ray, hit);
        out_ << "  ray " << k << ": o=" << fmt(ray.o) << " d=" << fmt(ray.d) << " -> ";
        if (!found) {
            out_ << "miss\n";
            return false;
        }
        Vec3f p = ray.o + hit.t * ray.d;
        uint32_t material = materialOf(hit);
        out_ << "hit t=" << hit.t << " p=" << fmt(p) << " ng=" << fmt(hit.ng) << " geom=" << hit.geomId << " prim=" << hit.primId;
        if (material < scene_.materials.size()) {
            const Material& m = scene_.materials[material];
            out_ << " material=" << material << " '" << m.name << "'";
            if (m.isEmissive()) out_ << " emission=" << fmt(Vec3f(m.emission.r, m.emission.g, m.emission.b));
        }
        out_ << "\n";
        if (!std::isfinite(hit.t) || !isFinite(p) || !isFinite(hit.ng))
            record_.noteNonFinite("hit of ray " + std::to_string(k) + " (t, point or normal)");
        return true;
    }
    bool occluded(const Ray& ray) const override {
        uint64_t k = ++record_.rays;
        noteNonFinite(ray, k);
        bool blocked = inner_.occluded(ray);
        out_ << "  shadow ray " << k << ": o=" << fmt(ray.o) << " d=" << fmt(ray.d) << " tMax=" << ray.tMax << " -> "
             << (blocked ? "occluded" : "visible") << "\n";
        return blocked;
    }

private:
    uint32_t materialOf(const Hit& h) const {
        const SceneGeometry& g = scene_.geometry;
        if (const TriangleMesh* mesh = g.meshOf(h.geomId, h.instId)) return mesh->materialId;
        if (h.geomId == g.sphereGeomId() && h.primId < g.spheres.size()) return g.spheres[h.primId].materialId;
        return kInvalidId;
    }
    void noteNonFinite(const Ray& ray, uint64_t k) const {
        if (!isFinite(ray.o)) record_.noteNonFinite("origin of ray " + std::to_string(k) + " " + fmt(ray.o));
        if (!isFinite(ray.d)) record_.noteNonFinite("direction of ray " + std::to_string(k) + " " + fmt(ray.d));
    }

    const Accel& inner_;
    const Scene& scene_;
    std::ostream& out_;
    SampleTrace& record_;
};

}  // namespace

SampleReplay replaySample(const RenderContext& ctx, const Integrator& integrator, SampleId id, uint64_t seed,
                          SamplerKind samplerKind, std::ostream& trace) {
    // The render's worker threads run with flush-to-zero (renderer.cpp); so must the replay.
    ScopedFlushToZero ftz;
    SampleTrace record;
    TracingAccel accel(ctx.accel, ctx.scene, trace, record);
    RenderContext traced{ctx.scene, accel, ctx.camera, ctx.maxDepth, &record};
    trace << "tessera: debug: replaying pixel (" << id.x << "," << id.y << ") sample " << id.sample << " seed " << seed
          << " with " << integrator.name() << " (sampler " << samplerName(samplerKind) << ")\n";
    // Exactly the renderer's sequence: Sampler(pixel, sample, seed, kind), jitter from its first 2D draw.
    Sampler sampler(Vec2i(id.x, id.y), id.sample, seed, samplerKind);
    {
        // What the render's pass prepared for this sample (a photon map), on the untraced context:
        // the trace lists the sample's own rays.
        ThreadPool pool(1);
        integrator.preparePass(ctx, id.sample, 1, seed, samplerKind, pool);
    }
    Vec2f raster = Vec2f(float(id.x), float(id.y)) + sampler.get2D();
    trace << "  raster (" << std::setprecision(9) << raster.x << ", " << raster.y << ")\n";
    SplatSink sink;
    SampleReplay r;
    r.radiance = integrator.sample(traced, Vec2i(id.x, id.y), raster, sampler, sink);
    r.splats = sink.entries();
    r.rays = record.rays;
    r.vertices = record.records().size();
    // What the integrator recorded between the rays above, one line per vertex or strategy.
    trace << "  path (" << integrator.name() << "):\n";
    record.print(trace);
    std::string first = record.firstNonFinite();
    for (size_t k = 0; k < r.splats.size(); ++k) {
        const SplatSink::Entry& e = r.splats[k];
        uint32_t x = e.pixelIndex % uint32_t(ctx.camera.width()), y = e.pixelIndex / uint32_t(ctx.camera.width());
        trace << "  splat " << k << " to pixel (" << x << "," << y << "): " << fmt(Vec3f(e.value.r, e.value.g, e.value.b)) << "\n";
        if (!isFinite(e.value)) {
            r.finite = false;
            if (first.empty()) first = "splat " + std::to_string(k) + " to pixel (" + std::to_string(x) + "," + std::to_string(y) + ")";
        }
    }
    trace << "  radiance " << fmt(Vec3f(r.radiance.r, r.radiance.g, r.radiance.b)) << " after " << r.rays << " rays, "
          << r.splats.size() << " splats\n";
    if (!isFinite(r.radiance)) {
        r.finite = false;
        if (first.empty()) first = "the returned radiance (every ray and hit was finite)";
    }
    if (!first.empty()) trace << "  first non-finite value: " << first << "\n";
    return r;
}

}  // namespace tessera
