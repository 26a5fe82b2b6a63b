#include "render/interrupt.h"

#include <signal.h>
#include <unistd.h>

#include "core/atomic_file.h"

namespace tessera {
namespace {
std::atomic<bool> gInterrupted{false};
struct sigaction gOldInt, gOldTerm;

extern "C" void onSignal(int) {
    if (gInterrupted.exchange(true)) {  // second signal: leave now (async-signal-safe calls only)
        removeTemporaryFileForSignal();  // an output being written (core/atomic_file.h)
        _exit(130);
    }
    const char msg[] = "\ntessera: interrupted, finishing the current tiles and writing the image (again to quit at once)\n";
    ssize_t ignored = write(STDERR_FILENO, msg, sizeof msg - 1);
    (void)ignored;
}
}  // namespace

static_assert(std::atomic<bool>::is_always_lock_free, "the interrupt flag is set from a signal handler");

std::atomic<bool>& interruptFlag() { return gInterrupted; }

InterruptGuard::InterruptGuard() {
    struct sigaction sa {};
    sa.sa_handler = onSignal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;
    sigaction(SIGINT, &sa, &gOldInt);
    sigaction(SIGTERM, &sa, &gOldTerm);
}

InterruptGuard::~InterruptGuard() {
    sigaction(SIGINT, &gOldInt, nullptr);
    sigaction(SIGTERM, &gOldTerm, nullptr);
}

}  // namespace tessera
