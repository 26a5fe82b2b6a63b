#pragma once
/// \file path_vertex.h
/// Sub-path vertices and random walks shared by light tracing (`lt`) and bidirectional path tracing
/// (`bdpt`). Notation after Veach 1997, ch. 10 and SmallVCM: a light sub-path y0 … y(s−1) starts on
/// a light, a camera sub-path z0 … z(t−1) at the camera. Every vertex stores
///  * `pdfFwdA`: area density of the vertex being sampled from its predecessor on its own sub-path;
///  * `pdfRevA`: area density of it being sampled from its successor, i.e. by a sub-path walking the
///    other way (filled in once the successor exists, and again for the connection).
/// A vertex reached by a delta scattering event stores the delta's unit weight converted to area,
/// |cos θ| / d² (deltaDensityA): every strategy that can build the path has the same delta factor
/// per specular vertex, so it cancels in the MIS ratios, but the conversion to area does not —
/// it is taken at the vertex after the specular one on one side and before it on the other.
/// Vertices "at infinity" (a light sub-path starting at the environment or a directional light, a
/// camera sub-path escaping to the environment) have a direction, not a position: densities towards
/// them stay in solid angle, and the density of the first vertex after one is the planar density of
/// the emission disk times the cosine there, with no distance (pbrt-v3 §16.3.1's infinite lights).
#include <vector>

#include "integrators/integrator.h"
#include "materials/surface_bsdf.h"

namespace tessera {

/// What a vertex is: the tag of a tagged struct (Tungsten), so no virtual call per vertex.
enum class VertexType : uint8_t { Camera, Light, Surface };

struct PathVertex {
    VertexType type = VertexType::Surface;
    Vec3f p{0.f};
    Vec3f ng{0.f};       ///< geometric normal (surfaces), emitter normal (area lights), view axis (camera); 0 for point
                         ///< and spot lights; for a vertex at infinity the unit direction towards it (from the scene)
    Vec3f ns{0.f};       ///< shading normal (surfaces; = ng otherwise)
    Vec3f woWorld{0.f};  ///< unit direction towards the previous vertex of its own sub-path (surfaces)
    Rgb beta{0.f};       ///< sub-path throughput up to this vertex (Veach's α, eq. 10.4/10.5)
    BsdfParams bsdf;     ///< the BSDF inputs at p (textures resolved), for surface vertices
    uint32_t lightIndex = kInvalidId;  ///< light vertex: its light; surface vertex: the emitter it lies on, if any
    Vec2f bary{0.f};     ///< barycentrics on its triangle (Hit's u, v): where an emissive texture is read
    bool delta = false;  ///< scattered by a delta BSDF here (cannot be a connection end)
    bool atInfinity = false;  ///< an infinite light's vertex (environment, directional): `ng` is its direction
    float pdfFwdA = 0.f;  ///< area density; solid angle for a vertex at infinity
    float pdfRevA = 0.f;
    /// BDPT's MIS prefix M_j through this vertex (bdpt_mis.h, eq. (†)); filled by bdptMisPrefixes
    /// once both sub-paths are traced.
    double misPrefix = 0.0;
    /// The segment to the predecessor on its own sub-path, from the two positions, as pdfBothWaysA
    /// computes it: the predecessor's position, the unit direction towards it and the length. Set by
    /// the random walks when both ends are points (toPrevLen > 0). Every density towards the
    /// predecessor (the walk's, and each connection's at this end) reuses it instead of a square
    /// root and three divisions; a copy of the vertex used next to another vertex (a test that
    /// rearranges a path) recomputes, as `prevP` tells.
    Vec3f prevP{0.f};
    Vec3f toPrev{0.f};
    float toPrevDist2 = 0.f, toPrevLen = 0.f;

    /// True where densities convert with the cosine at the vertex: surfaces and area-light points.
    bool onSurface() const {
        return type == VertexType::Surface || (type == VertexType::Light && !atInfinity && ng != Vec3f(0.f));
    }
    /// The normal used to offset shadow-ray ends (zero: no surface to leave, e.g. the lens, a point light).
    Vec3f offsetNormal() const { return type == VertexType::Camera ? Vec3f(0.f) : ng; }
    /// True when this vertex can end a connection edge (Veach's "connectible"): its BSDF has a
    /// non-delta lobe, even where its own walk sampled a delta one (a smooth coat over a diffuse base).
    /// A vertex at infinity is only ever reached by its own sub-path's direction (s = 0) or
    /// resampled (s = 1).
    bool connectible() const {
        return !atInfinity && (!delta || (type == VertexType::Surface && !isDeltaMaterial(bsdf)));
    }
};

/// Unit direction from vertex `a` towards vertex `b`, exact for vertices at infinity; zero when they coincide.
inline Vec3f directionTo(const PathVertex& a, const PathVertex& b) {
    if (b.atInfinity) return b.ng;
    if (a.atInfinity) return -a.ng;
    Vec3f w = b.p - a.p;
    float len = glm::length(w);
    return len > 0.f ? w / len : Vec3f(0.f);
}

/// Converts a solid-angle density at `from` into an area density at `to`: pdfW · |cos θ_to| / d²
/// (Veach 1997, eq. 8.10); no cosine when `to` is not on a surface; unchanged when `to` is at infinity.
float convertDensity(float pdfW, const PathVertex& from, const PathVertex& to);

/// The density of a delta scattering at `cur` towards `next` with the delta's weight set to 1,
/// converted to area at `next`: |cos θ_next| / d² (Veach 1997, §10.3.5; SmallVCM keeps the same
/// cos/d² through specular vertices). Storing 0 there instead (pbrt-v3's remap0) drops the
/// factor and misweights paths through mirrors: the ratio of two strategies then carries
/// d²(before)/d²(after) of the specular vertex, which on a caustic next to its mirror hands the
/// path to the strategy that samples it worst.
inline float deltaDensityA(const PathVertex& cur, const PathVertex& next) { return convertDensity(1.f, cur, next); }

/// Area density at `next` of `cur` sampling `next`, given that `cur` was reached from `prev`
/// (ignored for camera and light vertices): the BSDF, camera or light-emission direction density.
float pdfNextA(const RenderContext& ctx, const PathVertex* prev, const PathVertex& cur, const PathVertex& next);
/// pdfNextA(&pred, cur, b) and pdfNextA(&b, cur, pred) at once, bit-identical to the two calls:
/// for a surface vertex both densities share one BSDF, frame and side test (the walks and the
/// connection weights need both densities of the same vertex pair). `pred` is cur's predecessor on
/// its own sub-path (the segment to it is cur's cached toPrev when the walk set it).
void pdfBothWaysA(const RenderContext& ctx, const PathVertex& pred, const PathVertex& cur, const PathVertex& b, float& pdfToBA,
                  float& pdfToPredA);
/// pdfBothWaysA at a surface vertex whose BSDF a connection already built (to evaluate f there).
void pdfBothWaysA(const RenderContext& ctx, const SurfaceBsdf& bsdfAtCur, const PathVertex& pred, const PathVertex& cur,
                  const PathVertex& b, float& pdfToBA, float& pdfToPredA);
/// For a vertex on an emitter (light vertex, or a surface vertex with lightIndex): pdfPosA of the
/// light sub-path starting there (selection included); for a vertex at infinity the solid-angle
/// density of its direction (selection included).
float pdfLightOriginA(const RenderContext& ctx, const PathVertex& v);
/// For a vertex on an emitter: area density at `next` of the emitted direction towards `next`; for a
/// vertex at infinity the emission disk's 1/(π r²) times the cosine at `next`.
float pdfLightDirectionA(const RenderContext& ctx, const PathVertex& v, const PathVertex& next);

/// pdfLightOriginA(v) and pdfLightDirectionA(v, next) at once, bit-identical to the two calls.
void pdfLightBothA(const RenderContext& ctx, const PathVertex& v, const PathVertex& next, float& originA, float& towardsNextA);

/// Beer–Lambert transmittance of the segment between two vertices (integrators/volume.h): the one
/// rule every strategy applies to the same segment (random walks, connections, NEE, lens
/// connections), symmetric in `a` and `b`. Only surface vertices and points on area emitters can be
/// ends inside a volume; a vertex at infinity makes the segment infinitely long. `attenuates` is false (and the result 1)
/// when neither end lies on an attenuating volume's inside: callers then multiply nothing.
/// Inline for its first test: most scenes have no volume, and the walks and every connection ask.
Rgb segmentTransmittanceInVolumes(const RenderContext& ctx, const PathVertex& a, const PathVertex& b, bool& attenuates);
inline Rgb segmentTransmittance(const RenderContext& ctx, const PathVertex& a, const PathVertex& b, bool& attenuates) {
    attenuates = false;
    if (!ctx.scene.hasVolumes()) return Rgb(1.f);
    return segmentTransmittanceInVolumes(ctx, a, b, attenuates);
}

/// The "f" of a vertex towards `next` in a connection: BSDF (adjoint for importance, with the
/// shading correction), emitted radiance / intensity for light vertices, importance We for the camera.
Rgb evalVertex(const RenderContext& ctx, const PathVertex& v, const PathVertex& next, TransportMode mode);
/// evalVertex with the unit direction towards `next` already known (w == directionTo(v, next), non-zero).
Rgb evalVertexTowards(const RenderContext& ctx, const PathVertex& v, const Vec3f& w, TransportMode mode);
/// Emitted radiance of a surface vertex lying on a light, towards its predecessor, or of the
/// environment a camera sub-path escaped to (s = 0 strategy).
Rgb emittedAt(const RenderContext& ctx, const PathVertex& v);

/// Upper bound on sub-path vertices: a guard against lossless mirror boxes, never reached in practice
/// (Russian roulette ends paths; a path that long carries a negligible weight).
inline constexpr int kMaxSubpathVertices = 1024;

/// Traces the camera sub-path through `raster`: z0 (lens) then surface vertices (radiance transport),
/// ending with a vertex at infinity when a ray escapes a scene that has an environment.
/// At most `maxVertices` vertices (−1: unlimited, Russian roulette ends it).
void traceCameraSubpath(const RenderContext& ctx, Vec2f raster, Sampler& sampler, int maxVertices, std::vector<PathVertex>& out);
/// Traces a light sub-path: y0 on a light (picked ∝ power), then surface vertices (importance transport).
void traceLightSubpath(const RenderContext& ctx, Sampler& sampler, int maxVertices, std::vector<PathVertex>& out);

}  // namespace tessera
