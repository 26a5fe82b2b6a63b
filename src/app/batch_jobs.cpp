/// \file batch_jobs.cpp
#include "app/batch_jobs.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include "core/error.h"
#include "core/sampler_kind.h"

namespace tessera::app {
namespace {

using nlohmann::json;

/// One key of a JSON pointer (RFC 6901: '~' → "~0", '/' → "~1").
std::string pointerKey(const std::string& key) {
    std::string out;
    for (char c : key) out += c == '~' ? "~0" : c == '/' ? "~1" : std::string(1, c);
    return out;
}

/// Line and column (1-based) of a byte offset, for syntax errors.
std::string lineColumn(std::string_view text, size_t byte) {
    size_t line = 1, column = 1;
    for (size_t i = 0; i < byte && i < text.size(); ++i) {
        if (text[i] == '\n') {
            ++line;
            column = 1;
        } else {
            ++column;
        }
    }
    return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

/// Numbers in text that reads back as exactly the same float (9 significant digits round-trip).
std::string floatText(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", double(float(v)));
    return buf;
}

class Parser {
public:
    Parser(std::string path) : path_(std::move(path)), dir_(std::filesystem::path(path_).parent_path()) {}

    BatchFile parse(std::string_view text) {
        json root;
        try {
            root = json::parse(text.begin(), text.end());
        } catch (const json::parse_error& e) {
            // e.byte is one past the offending character.
            fail("", lineColumn(text, e.byte > 0 ? e.byte - 1 : 0) + ": not valid JSON (" + syntaxProblem(e) + ")");
        } catch (const json::exception& e) {  // e.g. a number too large for a double (out_of_range.406)
            fail("", "not valid JSON (" + syntaxProblem(e) + ")");
        }
        if (!root.is_object()) fail("", "must be a JSON object {\"defaults\": {...}, \"jobs\": [...]}");
        for (const auto& [key, value] : root.items())
            if (key != "defaults" && key != "jobs") fail("/" + pointerKey(key), "unknown key (expected \"defaults\" or \"jobs\")");

        Fields defaults;
        if (auto it = root.find("defaults"); it != root.end()) {
            if (!it->is_object()) fail("/defaults", "must be an object of job settings");
            apply(*it, "/defaults", defaults, false);
        }
        auto jobs = root.find("jobs");
        if (jobs == root.end()) fail("", "has no \"jobs\" array");
        if (!jobs->is_array()) fail("/jobs", "must be an array of job objects");
        if (jobs->empty()) fail("/jobs", "is empty: nothing to render");

        BatchFile file{path_, {}};
        std::map<std::string, std::string> outputs, names;  // → pointer of the job that has it
        for (size_t i = 0; i < jobs->size(); ++i) {
            const std::string ptr = "/jobs/" + std::to_string(i);
            const json& j = (*jobs)[i];
            if (!j.is_object()) fail(ptr, "must be an object of job settings");
            Fields f = defaults;
            apply(j, ptr, f, true);
            if (f.job.scene.empty()) fail(ptr, "has no \"scene\" (give it here or in /defaults)");
            if (f.job.output.empty())
                f.job.output = resolve("out/" + (f.name.empty() ? stem(f.job.scene) : f.name) + ".exr");
            if (auto [it, fresh] = outputs.emplace(f.job.output, ptr); !fresh)
                fail(ptr + "/output", "writes " + f.job.output + " like " + it->second + " does: give each job its own \"output\"");
            if (!f.name.empty())
                if (auto [it, fresh] = names.emplace(f.name, ptr); !fresh)
                    fail(ptr + "/name", "\"" + f.name + "\" names " + it->second + " too: names must be unique");
            BatchJob job;
            job.index = i;
            job.name = f.name;
            job.render = std::move(f.job);
            job.camera = f.camera;
            file.jobs.push_back(std::move(job));
        }
        return file;
    }

private:
    /// A job's settings while its defaults and its own keys are applied.
    struct Fields {
        RenderJob job;
        CameraChoice camera;
        std::string name;
    };

    [[noreturn]] void fail(const std::string& pointer, const std::string& problem) const {
        throw InputError(path_ + ": " + (pointer.empty() ? "" : pointer + ": ") + problem);
    }

    static std::string syntaxProblem(const json::exception& e) {
        // nlohmann's messages: "[json.exception.parse_error.101] parse error at line 1, column 5: syntax error while
        // parsing value - invalid literal; last read: 'x'" (keep what follows the position), or
        // "[json.exception.out_of_range.406] number overflow parsing '1e999'" (keep what follows the tag).
        std::string what = e.what();
        if (size_t at = what.find("parse error"); at != std::string::npos) {
            size_t colon = what.find(": ", at);
            return colon == std::string::npos ? what : what.substr(colon + 2);
        }
        size_t tag = what.find("] ");
        return tag == std::string::npos ? what : what.substr(tag + 2);
    }

    static std::string stem(const std::string& path) { return std::filesystem::path(path).stem().string(); }

    /// A path from the file: relative ones are relative to the JOBS file's folder.
    std::string resolve(const std::string& p) const {
        std::filesystem::path path(p);
        return (path.is_absolute() || dir_.empty() ? path : (dir_ / path)).lexically_normal().string();
    }

    std::string text(const json& v, const std::string& ptr) const {
        if (!v.is_string()) fail(ptr, "must be a string");
        std::string s = v.get<std::string>();
        if (s.empty()) fail(ptr, "must not be empty");
        if (s.find('\0') != std::string::npos) fail(ptr, "must not contain a NUL character");
        return s;
    }
    std::string pathValue(const json& v, const std::string& ptr) const { return resolve(text(v, ptr)); }

    int64_t integer(const json& v, const std::string& ptr, int64_t lo, int64_t hi) const {
        std::string range = "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
        if (!v.is_number_integer()) fail(ptr, "must be " + range);
        // Non-negative literals parse as unsigned: both bounds apply to them too ("spp": 0).
        if (v.is_number_unsigned() ? (v.get<uint64_t>() > uint64_t(hi) || (lo > 0 && v.get<uint64_t>() < uint64_t(lo)))
                                   : (v.get<int64_t>() < lo || v.get<int64_t>() > hi))
            fail(ptr, "must be " + range + ", got " + v.dump());
        return v.get<int64_t>();
    }

    /// A finite number in [lo, hi] (exclusive of lo when `aboveLo`).
    double number(const json& v, const std::string& ptr, double lo, double hi, bool aboveLo = false) const {
        if (!v.is_number()) fail(ptr, "must be a number");
        double x = v.get<double>();
        if (!std::isfinite(x) || x < lo || x > hi || (aboveLo && x == lo))
            fail(ptr, "must be a number " + std::string(aboveLo ? "> " : ">= ") + floatText(lo) + " and <= " + floatText(hi) +
                          ", got " + v.dump());
        return x;
    }

    /// [x, y, z] of finite numbers → "x,y,z".
    std::string vec3(const json& v, const std::string& ptr) const {
        if (!v.is_array() || v.size() != 3) fail(ptr, "must be an array of three numbers [x, y, z]");
        std::string out;
        for (size_t i = 0; i < 3; ++i) {
            out += i ? "," : "";
            out += floatText(number(v[i], ptr + "/" + std::to_string(i), -1e30, 1e30));
        }
        return out;
    }

    /// "camera": an index, a name, or {"index"|"name"|"look-at": ..., "fov": degrees}.
    void applyCamera(const json& v, const std::string& ptr, Fields& f) const {
        f.camera = CameraChoice{};
        f.job.lookAt.clear();
        f.job.fovDeg = 0.0;
        if (v.is_number()) {
            f.camera = {CameraChoice::Kind::Index, int(integer(v, ptr, 0, 1 << 30)), ""};
            return;
        }
        if (v.is_string()) {
            f.camera = {CameraChoice::Kind::Name, -1, text(v, ptr)};
            return;
        }
        if (!v.is_object())
            fail(ptr, "must be a camera index, a camera name or {\"look-at\": [eye, target, up], \"fov\": degrees}");
        int picks = 0;
        for (const auto& [key, value] : v.items()) {
            const std::string p = ptr + "/" + pointerKey(key);
            if (key == "index") {
                f.camera = {CameraChoice::Kind::Index, int(integer(value, p, 0, 1 << 30)), ""};
                ++picks;
            } else if (key == "name") {
                f.camera = {CameraChoice::Kind::Name, -1, text(value, p)};
                ++picks;
            } else if (key == "look-at") {
                if (!value.is_array() || value.size() < 2 || value.size() > 3)
                    fail(p, "must be [eye, target] or [eye, target, up], each [x, y, z]");
                for (size_t i = 0; i < value.size(); ++i) {
                    f.job.lookAt += i ? "," : "";
                    f.job.lookAt += vec3(value[i], p + "/" + std::to_string(i));
                }
                ++picks;
            } else if (key == "fov") {
                f.job.fovDeg = number(value, p, 0.001, 179.0);
            } else {
                fail(p, "unknown key (expected \"index\", \"name\", \"look-at\" or \"fov\")");
            }
        }
        if (picks > 1) fail(ptr, "give one of \"index\", \"name\" and \"look-at\"");
    }

    /// Applies the settings of one object (the defaults or a job) over `f`.
    void apply(const json& obj, const std::string& ptr, Fields& f, bool isJob) const {
        if (obj.contains("spp") && obj.contains("time")) fail(ptr, "give \"spp\" or \"time\", not both");
        RenderJob& r = f.job;
        for (const auto& [key, v] : obj.items()) {
            const std::string p = ptr + "/" + pointerKey(key);
            if (key == "name") {
                if (!isJob) fail(p, "a name belongs to one job, not to the defaults");
                f.name = text(v, p);
            } else if (key == "scene") {
                r.scene = pathValue(v, p);
            } else if (key == "camera") {
                applyCamera(v, p, f);
            } else if (key == "integrator") {
                r.integrator = text(v, p);
            } else if (key == "accel") {
                r.accel = text(v, p);
            } else if (key == "sampler") {
                r.sampler = text(v, p);
                if (!parseSamplerKind(r.sampler)) fail(p, "unknown sampler \"" + r.sampler + "\" (expected \"sobol\" or \"independent\")");
            } else if (key == "spp") {
                r.spp = int(integer(v, p, 1, 1 << 30));
                r.timeLimit = 0.0;  // a job's spp replaces the defaults' time
            } else if (key == "time") {
                r.timeLimit = number(v, p, 0.0, 1e9, true);
                r.spp = 0;
            } else if (key == "resolution") {
                r.resolution = text(v, p);
            } else if (key == "seed") {
                r.seed = integer(v, p, 0, INT64_MAX);
            } else if (key == "max-depth") {
                r.maxDepth = int(integer(v, p, -1, 1 << 20));
            } else if (key == "radius") {  // sppm, vcm: as render's --radius, --alpha, --photons
                r.photonRadius = float(number(v, p, 0.0, 1e30));
            } else if (key == "alpha") {
                r.photonAlpha = float(number(v, p, 0.01, 0.999));
            } else if (key == "photons") {
                r.photonPaths = uint64_t(integer(v, p, 1, int64_t(1) << 32));
            } else if (key == "output") {
                if (!isJob) fail(p, "an output belongs to one job, not to the defaults");
                r.output = pathValue(v, p);
            } else if (key == "png") {
                if (v.is_boolean()) {
                    r.noPng = !v.get<bool>();
                    r.png.clear();
                } else {
                    if (!isJob) fail(p, "a PNG path belongs to one job; the defaults may only say true or false");
                    r.png = pathValue(v, p);
                    r.noPng = false;
                }
            } else if (key == "display") {
                r.display = text(v, p);
            } else if (key == "view") {
                r.view = text(v, p);
            } else if (key == "env") {
                applyEnv(v, p, r);
            } else if (key == "env-rotate") {
                r.envRotate = number(v, p, -1e6, 1e6);
            } else if (key == "env-intensity") {
                r.envIntensity = number(v, p, 0.0, 1e30);
            } else if (key == "allow-external-files") {
                if (!v.is_boolean()) fail(p, "must be true or false");
                r.allowExternalFiles = v.get<bool>();
            } else if (key == "max-memory") {
                r.maxMemoryGiB = number(v, p, 0.001, 1e6);
            } else {
                fail(p, "unknown key (expected name, scene, camera, integrator, accel, sampler, spp, time, resolution, seed, "
                        "max-depth, radius, alpha, photons, output, png, display, view, env, env-rotate, env-intensity, "
                        "allow-external-files, max-memory)");
            }
        }
    }

    /// "env": an image file (relative to the JOBS file) or a constant colour [r, g, b].
    void applyEnv(const json& v, const std::string& ptr, RenderJob& r) const {
        if (v.is_array()) {
            if (v.size() != 3) fail(ptr, "a colour must be [r, g, b]");
            r.env.clear();
            for (size_t i = 0; i < 3; ++i) {
                r.env += i ? "," : "";
                r.env += floatText(number(v[i], ptr + "/" + std::to_string(i), 0.0, 1e30));
            }
            return;
        }
        // As with --env, text with commas that names no file is a colour "r,g,b".
        std::string given = text(v, ptr), resolved = resolve(given);
        std::error_code ec;
        r.env = given.find(',') != std::string::npos && !std::filesystem::exists(resolved, ec) ? given : resolved;
    }

    std::string path_;
    std::filesystem::path dir_;
};

}  // namespace

std::string BatchJob::label() const { return "/jobs/" + std::to_string(index) + (name.empty() ? "" : " (" + name + ")"); }

BatchFile parseBatchJobs(std::string_view text, const std::string& path) { return Parser(path).parse(text); }

BatchFile readBatchJobs(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path + ": no such file");
    uintmax_t bytes = std::filesystem::file_size(path, ec);
    if (ec) throw InputError(path + ": cannot read (" + ec.message() + ")");
    if (bytes > kMaxBatchFileBytes)
        throw InputError(path + ": " + std::to_string(bytes) + " bytes, over the limit of " + std::to_string(kMaxBatchFileBytes) +
                         " for a JOBS file");
    std::ifstream in(path, std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in && !in.eof()) throw InputError(path + ": cannot read");
    return parseBatchJobs(text, path);
}

}  // namespace tessera::app
