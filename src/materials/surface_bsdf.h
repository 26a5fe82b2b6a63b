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
#include "core/sampler.h"
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
    /// What a SurfaceBsdf will be asked. A Lambertian lobe's evaluation and densities need only the
    /// two cosines with the shading normal, so an evaluation-only BSDF of a diffuse point (two per
    /// bidirectional connection) skips the tangent frame, which only sample() and the other lobes use.
    enum class Use : uint8_t { EvalAndSample, EvalOnly };

    SurfaceBsdf(const BsdfParams& params, const Vec3f& ns, const Vec3f& ng, Use use = Use::EvalAndSample)
        : mat_(params), ng_(ng), delta_(isDeltaMaterial(params)) {
        if (use == Use::EvalOnly && mat_.type == MaterialType::Diffuse) {
            frame_.n = ns;
            tangentsSet_ = false;
        } else {
            frame_ = Frame(ns);
        }
    }

    /// True when every lobe is delta (no light sampling here); a mixed material (smooth coat over a
    /// diffuse base) is not, and each sample says whether it took a delta lobe (isDelta).
    bool isDelta() const { return delta_; }
    const Vec3f& ns() const { return frame_.n; }

    // eval, pdfFwdW, pdfBothW and evalWithPdf run several times per bidirectional connection:
    // defined here so that their side test and change of frame inline into the callers.

    /// f(wo, wi) for radiance; the adjoint f*(wo, wi) with the shading-normal correction for
    /// importance. Non-delta lobes only; zero for shading/geometric side mismatches.
    Rgb eval(const Vec3f& woWorld, const Vec3f& wiWorld, TransportMode mode) const {
        if (delta_ || !sidesAgree(woWorld, wiWorld)) return Rgb(0.f);
        if (mat_.type == MaterialType::Diffuse)  // two cosines, no change of frame (lambertEval)
            return lambertEval(mat_.baseColor, cosShading(woWorld), cosShading(wiWorld)) * shadingCorrection(woWorld, wiWorld, mode);
        // Reflection lobes are symmetric in their arguments; refraction is not, and evalBsdf returns
        // the adjoint for importance itself (the η² rule). The shading correction comes on top.
        Rgb f = evalBsdf(mat_, frame_.toLocal(woWorld), frame_.toLocal(wiWorld), mode);
        return f * shadingCorrection(woWorld, wiWorld, mode);
    }
    /// Solid-angle density of sampling wi given wo through the non-delta lobes (0 for delta materials).
    float pdfFwdW(const Vec3f& woWorld, const Vec3f& wiWorld) const {
        if (delta_ || !sidesAgree(woWorld, wiWorld)) return 0.f;
        if (mat_.type == MaterialType::Diffuse) return lambertPdfW(cosShading(woWorld), cosShading(wiWorld));
        return pdfBsdfW(mat_, frame_.toLocal(woWorld), frame_.toLocal(wiWorld));
    }
    /// pdfFwdW(wo, wi) and pdfFwdW(wi, wo) (the reverse density) with one change of frame and one
    /// side test (the test is symmetric in wo and wi).
    void pdfBothW(const Vec3f& woWorld, const Vec3f& wiWorld, float& pdfFwdW, float& pdfRevW) const {
        pdfFwdW = pdfRevW = 0.f;
        if (delta_ || !sidesAgree(woWorld, wiWorld)) return;
        if (mat_.type == MaterialType::Diffuse) {
            float cosO = cosShading(woWorld), cosI = cosShading(wiWorld);
            pdfFwdW = lambertPdfW(cosO, cosI);
            pdfRevW = lambertPdfW(cosI, cosO);
            return;
        }
        Vec3f woL = frame_.toLocal(woWorld), wiL = frame_.toLocal(wiWorld);
        pdfFwdW = pdfBsdfW(mat_, woL, wiL);
        pdfRevW = pdfBsdfW(mat_, wiL, woL);
    }
    /// eval and pdfFwdW together, with one change of frame and one side test: what light sampling
    /// needs to weight its sample against BSDF sampling.
    Rgb evalWithPdf(const Vec3f& woWorld, const Vec3f& wiWorld, TransportMode mode, float& pdfFwdW) const {
        pdfFwdW = 0.f;
        if (delta_ || !sidesAgree(woWorld, wiWorld)) return Rgb(0.f);
        if (mat_.type == MaterialType::Diffuse) {
            float cosO = cosShading(woWorld), cosI = cosShading(wiWorld);
            pdfFwdW = lambertPdfW(cosO, cosI);
            return lambertEval(mat_.baseColor, cosO, cosI) * shadingCorrection(woWorld, wiWorld, mode);
        }
        Vec3f woL = frame_.toLocal(woWorld), wiL = frame_.toLocal(wiWorld);
        return evalBsdfWithPdf(mat_, woL, wiL, mode, pdfFwdW) * shadingCorrection(woWorld, wiWorld, mode);
    }
    /// Samples wi given wo. False when no direction is produced or it violates the side rule. Not
    /// on a BSDF built with Use::EvalOnly.
    bool sample(const Vec3f& woWorld, float uLobe, Vec2f u, TransportMode mode, SurfaceBsdfSample& out) const;
    /// sample() with its numbers drawn from `sampler` in a fixed order, the lobe choice (1D) then
    /// the direction (2D). A number this material does not read is skipped, its slot consumed but
    /// not computed (a Sobol' draw is ~60 instructions): every later draw, and so the image, is
    /// what drawing it would give.
    bool sample(const Vec3f& woWorld, Sampler& sampler, TransportMode mode, SurfaceBsdfSample& out) const {
        float uLobe = 0.5f;
        Vec2f u(0.5f);
        if (sampleBsdfReadsLobeChoice(mat_)) uLobe = sampler.get1D();
        else sampler.skip1D();
        if (sampleBsdfReadsDirection(mat_)) u = sampler.get2D();
        else sampler.skip2D();
        return sample(woWorld, uLobe, u, mode, out);
    }

    /// The importance-transport shading-normal factor |wo·ns| |wi·ng| / (|wo·ng| |wi·ns|)
    /// (Veach 1997, eq. 5.19 with wo on the light side); 1 for radiance.
    float shadingCorrection(const Vec3f& woWorld, const Vec3f& wiWorld, TransportMode mode) const {
        if (mode == TransportMode::Radiance) return 1.f;
        // Veach 1997, §5.3: with shading normals the BSDF is not symmetric; the adjoint used for
        // importance (light sub-paths) is f*(wo→wi) = f(wi→wo) · |wo·ns| |wi·ng| / (|wo·ng| |wi·ns|).
        float num = std::abs(glm::dot(woWorld, frame_.n)) * std::abs(glm::dot(wiWorld, ng_));
        float den = std::abs(glm::dot(woWorld, ng_)) * std::abs(glm::dot(wiWorld, frame_.n));
        return den > 0.f ? num / den : 0.f;
    }

private:
    /// The local z of a world direction: frame_.toLocal(w).z, bit for bit.
    float cosShading(const Vec3f& w) const { return glm::dot(w, frame_.n); }
    /// True when wo → wi is on consistent sides of the shading and the geometric normal.
    bool sidesAgree(const Vec3f& wo, const Vec3f& wi) const {
        bool reflectShading = glm::dot(wo, frame_.n) * glm::dot(wi, frame_.n) > 0.f;
        bool reflectGeometric = glm::dot(wo, ng_) * glm::dot(wi, ng_) > 0.f;
        return reflectShading == reflectGeometric;
    }


    BsdfParams mat_;  ///< by value: textured points resolve their own parameters
    Frame frame_;     ///< only frame_.n is meaningful when tangentsSet_ is false (Use::EvalOnly, Lambertian)
    Vec3f ng_;
    bool delta_;      ///< isDeltaMaterial(mat_), asked once per point
    bool tangentsSet_ = true;
};

}  // namespace tessera
