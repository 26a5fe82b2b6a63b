#include "core/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cstring>
#include <filesystem>

#include "core/error.h"

namespace tessera {
namespace {

namespace fs = std::filesystem;

// The temporary file being written, if any: a NUL-terminated path a signal handler may unlink
// (a fixed buffer and a lock-free flag: nothing a handler cannot touch).
char gTemporaryPath[4096];
std::atomic<bool> gHasTemporaryPath{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the flag is read from a signal handler");

/// Registers a temporary path for removeTemporaryFileForSignal for its lifetime. One at a time;
/// longer paths are not registered.
class TemporaryFileForSignal {
public:
    explicit TemporaryFileForSignal(const std::string& path) {
        if (path.size() >= sizeof gTemporaryPath || gHasTemporaryPath.load()) return;
        std::memcpy(gTemporaryPath, path.c_str(), path.size() + 1);
        gHasTemporaryPath.store(true);
        registered_ = true;
    }
    ~TemporaryFileForSignal() {
        if (registered_) gHasTemporaryPath.store(false);
    }
    TemporaryFileForSignal(const TemporaryFileForSignal&) = delete;
    TemporaryFileForSignal& operator=(const TemporaryFileForSignal&) = delete;

private:
    bool registered_ = false;
};

/// Removes the temporary file on every exit path unless the rename succeeded, including exits by
/// exceptions thrown from inside the writer (OIIO, the allocator).
class TemporaryFileGuard {
public:
    explicit TemporaryFileGuard(std::string path) : path_(std::move(path)) {}
    ~TemporaryFileGuard() {
        if (!path_.empty()) {
            std::error_code ignored;
            fs::remove(path_, ignored);
        }
    }
    void release() { path_.clear(); }
    TemporaryFileGuard(const TemporaryFileGuard&) = delete;
    TemporaryFileGuard& operator=(const TemporaryFileGuard&) = delete;

private:
    std::string path_;
};

/// A temporary name beside `path`, unique per process and per call, so that two processes (or two
/// threads) writing the same destination never share a temporary file.
std::string temporaryPath(const std::string& path) {
    static std::atomic<unsigned> counter{0};
    return path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
}

}  // namespace

void writeFileAtomically(const std::string& path, const char* what,
                         const std::function<void(const std::string& temporaryPath)>& write) {
    const fs::path parent = fs::path(path).parent_path();
    if (!parent.empty()) {
        std::error_code ec;
        fs::create_directories(parent, ec);
        if (ec) throw InputError(path + ": cannot create directory " + parent.string() + ": " + ec.message());
    }
    const std::string tmp = temporaryPath(path);
    TemporaryFileGuard guard(tmp);
    TemporaryFileForSignal signalCleanup(tmp);
    write(tmp);
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) throw InputError(path + ": cannot replace " + what + ": " + ec.message());
    guard.release();
}

void removeTemporaryFileForSignal() {
    if (gHasTemporaryPath.load()) unlink(gTemporaryPath);
}

}  // namespace tessera
