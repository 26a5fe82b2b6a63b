#include "integrators/integrator.h"

#include "core/error.h"
#include "integrators/bdpt.h"
#include "integrators/bsdf_path_tracer.h"
#include "integrators/light_tracer.h"
#include "integrators/path_tracer.h"

namespace tessera {

/// `bdpt-balance` is bdpt with the balance heuristic (β = 1) instead of the power heuristic.
std::vector<std::string> integratorNames() { return {"pt", "ptnee", "lt", "bdpt", "bdpt-balance"}; }

std::unique_ptr<Integrator> createIntegrator(std::string_view name) {
    if (name == "pt") return std::make_unique<BsdfPathTracer>();
    if (name == "ptnee") return std::make_unique<PathTracer>();
    if (name == "lt") return std::make_unique<LightTracer>();
    if (name == "bdpt") return std::make_unique<BdptIntegrator>();
    if (name == "bdpt-balance") return std::make_unique<BdptIntegrator>(BdptSettings{MisHeuristic::Balance});
    std::string known;
    for (const std::string& n : integratorNames()) known += (known.empty() ? "" : ", ") + n;
    throw InputError("unknown integrator '" + std::string(name) + "' (known: " + known + ")");
}

}  // namespace tessera
