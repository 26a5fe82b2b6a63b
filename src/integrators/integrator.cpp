#include "integrators/integrator.h"

#include "core/error.h"
#include "integrators/path_tracer.h"

namespace tessera {

std::vector<std::string> integratorNames() { return {"ptnee"}; }

std::unique_ptr<Integrator> createIntegrator(std::string_view name) {
    if (name == "ptnee") return std::make_unique<PathTracer>();
    std::string known;
    for (const std::string& n : integratorNames()) known += (known.empty() ? "" : ", ") + n;
    throw InputError("unknown integrator '" + std::string(name) + "' (known: " + known + ")");
}

}  // namespace tessera
