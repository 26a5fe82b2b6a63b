#pragma once
/// \file script.h
/// `tessera view --script FILE`: timed input events that drive the preview exactly as a user would
/// (they go through the same handlers as the window's events), for deterministic tests and demos.
///
/// One event per line, '#' starts a comment; SECONDS counts from the window opening:
///     SECONDS down KEY | up KEY | press KEY     a key (press = down and up at the same instant)
///     SECONDS look DX DY                        relative mouse motion in pixels (+x right, +y down)
///     SECONDS click                             a left click in the window (captures the mouse)
///     SECONDS quit                              closes the window
/// KEY: a letter or digit, or space, ctrl, shift, escape.
#include <string>
#include <vector>

namespace tessera::view {

struct ScriptEvent {
    enum class Kind { Down, Up, Press, Look, Click, Quit };
    double seconds = 0.0;
    Kind kind = Kind::Quit;
    std::string key;  ///< Down/Up/Press: the key's name, lower case
    double dx = 0.0, dy = 0.0;
    int line = 0;
};

/// Parses a script; the events come back sorted by time (stable for equal times). Throws
/// InputError "FILE:LINE: problem" on a malformed line, an unknown key or a negative time.
std::vector<ScriptEvent> parseScript(const std::string& text, const std::string& fileName);
/// Reads and parses FILE (InputError if it cannot be read).
std::vector<ScriptEvent> readScript(const std::string& path);

}  // namespace tessera::view
