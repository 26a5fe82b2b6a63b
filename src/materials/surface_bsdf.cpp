#include "materials/surface_bsdf.h"

#include <cassert>

namespace tessera {

bool SurfaceBsdf::sample(const Vec3f& wo, float uLobe, Vec2f u, TransportMode mode, SurfaceBsdfSample& out) const {
    assert(tangentsSet_ && "sample() on a SurfaceBsdf built with Use::EvalOnly");
    Vec3f woL = frame_.toLocal(wo);
    BsdfSample bs;
    if (!sampleBsdf(mat_, woL, uLobe, u, mode, bs)) return false;
    Vec3f wi = frame_.toWorld(bs.wiLocal);
    if (!sidesAgree(wo, wi)) return false;
    out.wiWorld = wi;
    out.isDelta = bs.isDelta;
    out.eta = bs.eta;
    out.pdfFwdW = bs.pdfW;
    out.weight = bs.weight * shadingCorrection(wo, wi, mode);
    return true;
}

}  // namespace tessera
