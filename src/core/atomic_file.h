#pragma once
/// \file atomic_file.h
/// Writing a file so that no reader (and no crash) ever sees it half-written: images and checkpoints
/// alike go through writeFileAtomically.
#include <functional>
#include <string>

namespace tessera {

/// Writes `path` atomically. `write` fills a temporary file beside `path` (same directory, so the
/// final rename stays within one file system), which is then renamed over `path`: rename() is
/// atomic, so readers see either the old file or the complete new one. Creates the parent
/// directory. The temporary file is removed on every failure, exceptions from `write` included,
/// and by a second Ctrl-C's immediate exit (render/interrupt.h calls removeTemporaryFileForSignal).
/// `what` names the file in error messages ("cannot replace <what>").
/// Throws InputError when the directory cannot be created or the rename fails.
void writeFileAtomically(const std::string& path, const char* what,
                         const std::function<void(const std::string& temporaryPath)>& write);

/// Unlinks the temporary file writeFileAtomically is writing, if any. Async-signal-safe: for a
/// signal handler that is about to _exit().
void removeTemporaryFileForSignal();

}  // namespace tessera
