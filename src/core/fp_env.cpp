#include "core/fp_env.h"

#if defined(__SSE__) || defined(__x86_64__)
#include <pmmintrin.h>
#include <xmmintrin.h>
#define TESSERA_HAS_MXCSR 1
#endif

namespace tessera {
void enableFlushToZero() {
#if defined(TESSERA_HAS_MXCSR)
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#endif
}

ScopedFlushToZero::ScopedFlushToZero() {
#if defined(TESSERA_HAS_MXCSR)
    saved_ = _mm_getcsr();
    enableFlushToZero();
#endif
}

ScopedFlushToZero::~ScopedFlushToZero() {
#if defined(TESSERA_HAS_MXCSR)
    _mm_setcsr(saved_);
#endif
}
}  // namespace tessera
