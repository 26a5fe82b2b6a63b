#include "integrators/vcm.h"

#include "integrators/bdpt_connect.h"
#include "integrators/sample_trace.h"
#include "materials/surface_bsdf.h"

namespace tessera {

// Why this converges (Georgiev et al. 2012, §4–5). Every path x0 … xk is produced by the k + 1
// connection strategies of bdpt and by k − 1 merges, one per interior vertex x_i: the light
// sub-path reaches x_i, a camera sub-path reaches a point within r of it, and the merge estimates
//     f(x) / p_VM(x),   p_VM = p_conn(light x0 … x_i, camera x(i+1) … xk) · p←(x_i) · N π r²
// (the tech report's eq. 19–21: N light sub-paths, each a chance π r² p←(x_i) that the camera
// vertex falls within r). With the weights of bdpt_mis.h's (‡) summing to one over connections
// and merges, the combination is unbiased up to the merges' kernel: each merge blurs the
// radiance over a disk of radius r_i, a bias of O(r_i²) that the Knaus–Zwicker radius sequence
// (photon_pass.h) drives to zero while the merges' variance, O(1/(N r_i²)), averaged over
// iterations still falls: consistent, like sppm. Where connections sample a path well their
// weight takes it whole (the merge's density carries N π r² p←, tiny next to a connection's
// densities for diffuse paths), so vcm is never far from bdpt; on SDS paths no connection
// exists and the merges carry them alone.

namespace {

/// η = N π r² (tech report eq. 21 with one connected light sub-path per camera sample, n_VC = 1).
double etaOf(uint64_t paths, float radius) { return double(paths) * double(kPi) * double(radius) * double(radius); }

/// What a camera vertex z(t−1) contributes to the weight of every merge there. The reference
/// strategy is the connection of the merge's path that joins y_j (the photon, at z(t−1)) to
/// z(t−2): every other strategy is a ratio to it, as in bdpt_mis.h.
struct MergeSite {
    MisHeuristic heuristic;
    /// Unit direction from z(t−1) towards z(t−2) from their positions (the walk's cached segment),
    /// not the ray's: every density of the path is taken between positions, so the weights of
    /// merges and connections sum to one even where the two differ (vertices a hair apart in a corner).
    Vec3f toCamera{0.f};
    double q = 0.0;        ///< (η p←(x))^β: the merge itself, relative to the reference
    double fwdX = 1.0;     ///< p←(x): the camera walk's density of z(t−1)
    double self = 1.0;     ///< the reference connection exists (z(t−2) not delta)
    bool cameraSide = false;  ///< t ≥ 3: strategies with fewer camera vertices than the reference
    double camTerm = 0.0;  ///< (‡)'s bracket at z(t−2)
    double camFwd = 1.0;   ///< p←(z(t−2))
    float camConv = 0.f;   ///< solid angle at z(t−1) → area at z(t−2)
};

MergeSite mergeSiteOf(std::span<const PathVertex> camera, int t, double eta, MisHeuristic heuristic) {
    using mis_detail::remap0;
    const PathVertex& x = camera[size_t(t - 1)];
    MergeSite m{heuristic};
    m.toCamera = x.toPrevLen > 0.f && x.prevP == camera[size_t(t - 2)].p ? x.toPrev : directionTo(x, camera[size_t(t - 2)]);
    m.fwdX = remap0(x.pdfFwdA);
    m.q = mis_detail::powBeta(eta * m.fwdX, heuristic);
    if (t >= 3) {
        // z(t−2) becomes light-sampled in the strategies beyond the reference: its density from
        // the light side is the BSDF at x towards it (given the photon's direction), per photon.
        const PathVertex& e = camera[size_t(t - 2)];
        m.self = e.delta ? 0.0 : 1.0;
        m.cameraSide = true;
        m.camFwd = remap0(e.pdfFwdA);
        m.camConv = convertDensity(1.f, x, e);
        const bool connects = !e.delta && !camera[size_t(t - 3)].delta;
        m.camTerm = misPrefixTerm(camera[size_t(t - 3)].misPrefix, connects, 1.0, misMergeTerm(!e.delta, e.pdfFwdA, eta, heuristic));
    }
    return m;
}

/// The merge's weight from the camera BSDF's two densities at x: towards the photon's
/// predecessor (given the camera direction) and towards z(t−2) (given the photon's direction).
float mergeWeight(const MergeSite& m, const VcmPhoton& ph, float pdfToPhotonW, float pdfToCameraW) {
    using mis_detail::powBeta;
    using mis_detail::remap0;
    // Light side: y_j's ratio r_j, then the strategies at and beyond y(j−1) (the tech report's
    // dVCM/dVM of the light vertex, eq. 38), the merge at x itself being rX · μ_x = q.
    const double rX = powBeta(m.fwdX / remap0(ph.pdfFwdA), m.heuristic);
    const double restLight = powBeta(remap0(pdfToPhotonW * ph.toPrevConv), m.heuristic) * ph.restOverFwd;
    double sum = m.self + rX * (ph.connTerm + restLight) + m.q;
    if (m.cameraSide) sum += powBeta(remap0(pdfToCameraW * m.camConv) / m.camFwd, m.heuristic) * m.camTerm;
    return float(m.q / sum);
}

}  // namespace

void vcmPhotonsOfPath(const RenderContext& ctx, std::span<const PathVertex> path, MisHeuristic heuristic, double eta,
                      std::vector<VcmPhoton>& photons, std::vector<Vec3f>& positions) {
    if (path.size() < 2) return;
    const bool lightIsDelta = ctx.scene.lights().isDelta(path[0].lightIndex);
    const double g1 = bdptLightNeeFactor(ctx, path, heuristic);
    for (size_t j = 1; j < path.size(); ++j) {
        const PathVertex& v = path[j];
        // A vertex whose material has no non-delta lobe reflects nothing a merge can see.
        if (v.type != VertexType::Surface || isDeltaMaterial(v.bsdf)) continue;
        const PathVertex& prev = path[j - 1];
        const size_t i = j - 1;
        // (‡) at y_i = y(j−1) as bdptMisPrefixes writes it, without its ratio r_i: the merge knows
        // p←(y_i) only once it knows the camera direction.
        const bool prevPrevDelta = i >= 1 ? path[i - 1].delta : lightIsDelta;
        const double mu = misMergeTerm(i >= 1 && !prev.delta, prev.pdfFwdA, eta, heuristic);
        const double term = misPrefixTerm(i >= 1 ? path[i - 1].misPrefix : 0.0, !prev.delta && !prevPrevDelta, i == 1 ? g1 : 1.0, mu);
        VcmPhoton ph;
        // From the positions, as every density of the path (the walk's cached segment when it is this one).
        ph.wi = v.toPrevLen > 0.f && v.prevP == prev.p ? v.toPrev : directionTo(v, prev);
        ph.power = v.beta;
        ph.depth = uint32_t(j);
        ph.pdfFwdA = v.pdfFwdA;
        ph.toPrevConv = convertDensity(1.f, v, prev);
        ph.connTerm = prev.delta ? 0.0 : (j == 1 ? g1 : 1.0);  // y_j scatters through a non-delta lobe here
        ph.restOverFwd = term / mis_detail::powBeta(mis_detail::remap0(prev.pdfFwdA), heuristic);
        photons.push_back(ph);
        positions.push_back(v.p);
    }
}

float vcmMergeWeight(const RenderContext&, const VcmPhoton& photon, std::span<const PathVertex> camera, int t,
                     const SurfaceBsdf& bsdfAtX, double eta, MisHeuristic heuristic) {
    const MergeSite site = mergeSiteOf(camera, t, eta, heuristic);
    float toPhoton, toCamera;
    bsdfAtX.pdfBothW(site.toCamera, photon.wi, toPhoton, toCamera);
    return mergeWeight(site, photon, toPhoton, toCamera);
}

void VcmIntegrator::preparePass(const RenderContext& ctx, uint32_t firstSample, uint32_t count, uint64_t seed, SamplerKind kind,
                                ThreadPool& pool) const {
    if (count == 0 || photons_.radius == 0.f) return;
    pass_.prepare(ctx, photons_, firstSample, seed, kind, pool,
                  [this, &ctx](std::vector<PathVertex>& path, std::vector<VcmPhoton>& photons, std::vector<Vec3f>& positions) {
                      // prepare() has set the iteration's radius and path count before tracing.
                      const double eta = etaOf(pass_.paths, pass_.radius);
                      bdptMisPrefixes(ctx, path, {}, heuristic_, eta);
                      vcmPhotonsOfPath(ctx, path, heuristic_, eta, photons, positions);
                  });
}

Rgb VcmIntegrator::sample(const RenderContext& ctx, Vec2i, Vec2f raster, Sampler& sampler, SplatSink& splats) const {
    const bool merging = photons_.radius != 0.f;
    if (merging) pass_.requireIteration(sampler, "vcm");
    thread_local std::vector<PathVertex> camera, light;
    const int maxDepth = ctx.maxDepth;
    // The sub-paths and connections of bdpt, drawn from the same numbers.
    const double eta = merging ? etaOf(pass_.paths, pass_.radius) : 0.0;
    traceBdptSubpaths(ctx, raster, sampler, heuristic_, eta, camera, light);
    BdptSettings connections;
    connections.heuristic = heuristic_;
    Rgb L = connectAllStrategies(ctx, light, camera, sampler, splats, connections, eta);
    if (!(eta > 0.0)) return L;

    // Merges at every camera vertex after the lens with a non-delta lobe (the estimator of the
    // tech report's eq. 24 with the weights of eq. 42): Σ_photons w · f · α_L / (N π r²).
    const float norm = float(1.0 / eta);
    for (int t = 2; t <= int(camera.size()); ++t) {
        const PathVertex& x = camera[size_t(t - 1)];
        if (maxDepth >= 0 && t - 1 > maxDepth) break;  // a photon has j ≥ 1: j + t − 2 bounces
        if (x.type != VertexType::Surface || isDeltaMaterial(x.bsdf)) continue;
        const SurfaceBsdf bsdf(x.bsdf, x.ns, x.ng, SurfaceBsdf::Use::EvalOnly);
        const MergeSite site = mergeSiteOf(camera, t, eta, heuristic_);
        Rgb sum(0.f);
        pass_.grid.forEachWithin(x.p, pass_.radius, [&](uint32_t i) {
            const VcmPhoton& ph = pass_.photons[i];
            if (maxDepth >= 0 && int(ph.depth) + t - 2 > maxDepth) return;
            Rgb f = bsdf.eval(x.woWorld, ph.wi, TransportMode::Radiance);
            if (isBlack(f)) return;
            float toPhoton, toCamera;
            bsdf.pdfBothW(site.toCamera, ph.wi, toPhoton, toCamera);
            sum += f * ph.power * mergeWeight(site, ph, toPhoton, toCamera);
        });
        Rgb c = x.beta * sum * norm;
        if (ctx.trace) [[unlikely]] {
            ctx.trace->begin("merge", t - 1);
            ctx.trace->add("contribution", c);
        }
        L += c;
    }
    return L;
}

}  // namespace tessera
