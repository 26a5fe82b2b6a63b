#include "view/script.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace tessera::view {
namespace {

bool knownKey(const std::string& k) {
    if (k.size() == 1) return std::isalnum(static_cast<unsigned char>(k[0])) != 0;
    return k == "space" || k == "ctrl" || k == "shift" || k == "escape";
}

}  // namespace

std::vector<ScriptEvent> parseScript(const std::string& text, const std::string& fileName) {
    std::vector<ScriptEvent> events;
    std::istringstream in(text);
    std::string line;
    int lineNo = 0;
    while (std::getline(in, line)) {
        ++lineNo;
        if (size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
        std::istringstream ls(line);
        std::string timeText, verb;
        if (!(ls >> timeText)) continue;  // blank or comment
        auto fail = [&](const std::string& why) -> InputError {
            return InputError(fileName + ":" + std::to_string(lineNo) + ": " + why);
        };
        ScriptEvent e;
        e.line = lineNo;
        try {
            size_t used = 0;
            e.seconds = std::stod(timeText, &used);
            if (used != timeText.size()) throw std::invalid_argument(timeText);
        } catch (const std::exception&) {
            throw fail("'" + timeText + "' is not a time in seconds");
        }
        if (!std::isfinite(e.seconds) || e.seconds < 0.0) throw fail("the time must be a finite number of seconds >= 0");
        if (!(ls >> verb)) throw fail("an event (down, up, press, look, click, quit) must follow the time");
        if (verb == "down" || verb == "up" || verb == "press") {
            e.kind = verb == "down" ? ScriptEvent::Kind::Down : verb == "up" ? ScriptEvent::Kind::Up : ScriptEvent::Kind::Press;
            if (!(ls >> e.key)) throw fail(verb + " needs a key");
            std::transform(e.key.begin(), e.key.end(), e.key.begin(), [](unsigned char c) { return char(std::tolower(c)); });
            if (!knownKey(e.key)) throw fail("unknown key '" + e.key + "' (a letter, a digit, space, ctrl, shift or escape)");
        } else if (verb == "look") {
            e.kind = ScriptEvent::Kind::Look;
            if (!(ls >> e.dx >> e.dy) || !std::isfinite(e.dx) || !std::isfinite(e.dy)) throw fail("look needs DX DY in pixels");
        } else if (verb == "click") {
            e.kind = ScriptEvent::Kind::Click;
        } else if (verb == "quit") {
            e.kind = ScriptEvent::Kind::Quit;
        } else {
            throw fail("unknown event '" + verb + "' (down, up, press, look, click, quit)");
        }
        std::string extra;
        if (ls >> extra) throw fail("unexpected '" + extra + "' after the event");
        events.push_back(e);
    }
    std::stable_sort(events.begin(), events.end(), [](const ScriptEvent& a, const ScriptEvent& b) { return a.seconds < b.seconds; });
    return events;
}

std::vector<ScriptEvent> readScript(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw InputError(path + ": cannot read the script");
    std::ostringstream ss;
    ss << f.rdbuf();
    return parseScript(ss.str(), path);
}

}  // namespace tessera::view
