#include "scene/gltf_components.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cstdint>
#include <cstring>

namespace tessera {

float componentAsFloat(const unsigned char* p, int componentType, bool normalized) {
    switch (componentType) {
        case TINYGLTF_COMPONENT_TYPE_BYTE: {
            auto c = float(int8_t(p[0]));
            return normalized ? std::max(c / 127.f, -1.f) : c;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? float(p[0]) / 255.f : float(p[0]);
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
            int16_t c;
            std::memcpy(&c, p, 2);
            return normalized ? std::max(float(c) / 32767.f, -1.f) : float(c);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t c;
            std::memcpy(&c, p, 2);
            return normalized ? float(c) / 65535.f : float(c);
        }
        default: {
            float f;
            std::memcpy(&f, p, 4);
            return f;
        }
    }
}

}  // namespace tessera
