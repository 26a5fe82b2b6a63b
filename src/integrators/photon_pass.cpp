#include "integrators/photon_pass.h"

namespace tessera {

float photonIterationRadius(float radius, float alpha, uint32_t iteration) {
    double r2 = double(radius) * double(radius);
    for (uint32_t k = 1; k <= iteration; ++k) r2 *= (double(k) + double(alpha)) / double(k + 1);
    return float(std::sqrt(r2));
}

}  // namespace tessera
