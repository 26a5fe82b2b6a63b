#include "integrators/integrator.h"

#include "core/error.h"
#include "integrators/bdpt.h"
#include "integrators/lt.h"
#include "integrators/pt.h"
#include "integrators/ptnee.h"
#include "integrators/sppm.h"
#include "integrators/vcm.h"

namespace tessera {

/// `bdpt-balance` is bdpt with the balance heuristic (β = 1) instead of the power heuristic.
std::vector<std::string> integratorNames() { return {"pt", "ptnee", "lt", "bdpt", "bdpt-balance", "sppm", "vcm"}; }

std::unique_ptr<Integrator> createIntegrator(const RenderSettings& s) {
    const PhotonSettings photons{s.photonRadius, s.photonAlpha, s.photonPaths};
    if (s.integrator == "sppm") return std::make_unique<SppmIntegrator>(photons);
    if (s.integrator == "vcm") return std::make_unique<VcmIntegrator>(photons);
    return createIntegrator(s.integrator);
}

std::unique_ptr<Integrator> createIntegrator(std::string_view name) {
    if (name == "pt") return std::make_unique<PtIntegrator>();
    if (name == "ptnee") return std::make_unique<PtNeeIntegrator>();
    if (name == "lt") return std::make_unique<LtIntegrator>();
    if (name == "bdpt") return std::make_unique<BdptIntegrator>();
    if (name == "bdpt-balance") return std::make_unique<BdptIntegrator>(BdptSettings{MisHeuristic::Balance});
    if (name == "sppm") return std::make_unique<SppmIntegrator>();
    if (name == "vcm") return std::make_unique<VcmIntegrator>();
    std::string known;
    for (const std::string& n : integratorNames()) known += (known.empty() ? "" : ", ") + n;
    throw InputError("unknown integrator '" + std::string(name) + "' (known: " + known + ")");
}

}  // namespace tessera
