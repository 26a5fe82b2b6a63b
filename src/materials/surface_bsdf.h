#pragma once
/// \file surface_bsdf.h
/// A material bound to one surface point: the world-space BSDF interface that bidirectional methods
/// need. It adds to bsdf.h (local frame, radiance only)
///  * the density pdfFwdW = p(wi | wo); with the arguments swapped it is the reverse density
///    p(wo | wi) that a sub-path walking the other way would have used (Veach 1997, §10.2);
///  * the adjoint BSDF for importance transport with shading normals (Veach 1997, §5.3, eq. 5.17 ff.):
///    f*(wo→wi) carries the factor |wo·ns| |wi·ng| / (|wo·ng| |wi·ns|), which makes light sub-paths
///    and camera sub-paths agree (missing in pbrt-v3 until PR #94);
///  * the geometric-side rule: a scattering event counts as a reflection only if wo and wi lie on the
///    same side of the *geometric* surface as well as of the shading normal; otherwise it is zero
///    (no light leaks through interpolated normals, Veach 1997, §5.3).
/// Directions are world space and point away from the surface (`woWorld` towards the previous path
/// vertex, `wiWorld` towards the next one).
#include "core/frame.h"
#include "materials/bsdf.h"

namespace tessera {

struct SurfaceBsdfSample {
    Vec3f wiWorld{0.f};
    Rgb weight{0.f};      ///< f · |wi·ns| / pdfFwdW, shading correction included in importance mode
    float pdfFwdW = 0.f;  ///< density of wi given wo (for delta lobes: the lobe's discrete probability)
    bool isDelta = false;
    float eta = 1.f;      ///< η_t/η_i of a refraction, 1 otherwise
};

class SurfaceBsdf {
public:
    SurfaceBsdf(const BsdfParams& params, const Vec3f& ns, const Vec3f& ng) : mat_(params), frame_(ns), ng_(ng) {}

    /// True when every lobe is delta (no light sampling here); a mixed material (smooth coat over a
    /// diffuse base) is not, and each sample says whether it took a delta lobe (isDelta).
    bool isDelta() const { return isDeltaMaterial(mat_); }
    const Vec3f& ns() const { return frame_.n; }

    /// f(wo, wi) for radiance; the adjoint f*(wo, wi) with the shading-normal correction for
    /// importance. Non-delta lobes only; zero for shading/geometric side mismatches.
    Rgb eval(const Vec3f& woWorld, const Vec3f& wiWorld, TransportMode mode) const;
    /// Solid-angle density of sampling wi given wo through the non-delta lobes (0 for delta materials).
    float pdfFwdW(const Vec3f& woWorld, const Vec3f& wiWorld) const;
    /// pdfFwdW(wo, wi) and pdfFwdW(wi, wo) (the reverse density) with one change of frame and one
    /// side test (the test is symmetric in wo and wi).
    void pdfBothW(const Vec3f& woWorld, const Vec3f& wiWorld, float& pdfFwdW, float& pdfRevW) const;
    /// eval and pdfFwdW together, with one change of frame and one side test: what light sampling
    /// needs to weight its sample against BSDF sampling.
    Rgb evalWithPdf(const Vec3f& woWorld, const Vec3f& wiWorld, TransportMode mode, float& pdfFwdW) const;
    /// Samples wi given wo. False when no direction is produced or it violates the side rule.
    bool sample(const Vec3f& woWorld, float uLobe, Vec2f u, TransportMode mode, SurfaceBsdfSample& out) const;

    /// The importance-transport shading-normal factor |wo·ns| |wi·ng| / (|wo·ng| |wi·ns|)
    /// (Veach 1997, eq. 5.19 with wo on the light side); 1 for radiance.
    float shadingCorrection(const Vec3f& woWorld, const Vec3f& wiWorld, TransportMode mode) const;

private:
    /// True when wo → wi is on consistent sides of the shading and the geometric normal.
    bool sidesAgree(const Vec3f& woWorld, const Vec3f& wiWorld) const;

    BsdfParams mat_;  ///< by value: textured points resolve their own parameters
    Frame frame_;
    Vec3f ng_;
};

}  // namespace tessera
