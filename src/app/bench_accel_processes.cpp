/// \file bench_accel_processes.cpp
/// `tessera bench-accel --processes N`: the benchmark run in N fresh processes, one after another,
/// each re-executing this program with `--json`, and every figure reported as the median over the
/// processes with its spread. Why processes and not more repeats: on this code one ray kind of any
/// structure (Embree's included) may run 25–40% slower for a whole process, drawn afresh at each
/// start (the address-space layout: stack, heap and library placement are randomised per process),
/// while the repeats inside one process agree; only a sample of processes shows that spread and
/// gives a median that does not depend on one draw.
#include "app/bench_accel_processes.h"

#include <nlohmann/json.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include "core/error.h"

namespace tessera::app {
namespace {

/// Runs `argv` (argv[0] a path) with stdout captured; throws on a failed start or a non-zero exit.
std::string runCaptured(const std::vector<std::string>& argv) {
    int fds[2];
    if (pipe(fds) != 0) throw std::runtime_error(std::string("bench-accel --processes: pipe: ") + std::strerror(errno));
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    std::cout.flush();
    pid_t pid = fork();
    if (pid < 0) throw std::runtime_error(std::string("bench-accel --processes: fork: ") + std::strerror(errno));
    if (pid == 0) {
        dup2(fds[1], STDOUT_FILENO);
        close(fds[0]);
        close(fds[1]);
        execv(args[0], args.data());
        _exit(127);
    }
    close(fds[1]);
    std::string out;
    char buf[65536];
    for (ssize_t n; (n = read(fds[0], buf, sizeof buf)) != 0;) {
        if (n < 0) {
            if (errno == EINTR) continue;
            break;
        }
        out.append(buf, size_t(n));
    }
    close(fds[0]);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        throw std::runtime_error("bench-accel --processes: a benchmark process failed (exit status " +
                                 std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")");
    return out;
}

/// Median, smallest and largest of the processes' values, and the spread (largest − smallest) /
/// median: the figure the "agree within 5%" target is about.
struct Summary {
    double median = 0, min = 0, max = 0, spread = 0;
    std::vector<double> values;
};

Summary summarise(std::vector<double> v) {
    Summary s;
    s.values = v;
    if (v.empty()) return s;
    std::sort(v.begin(), v.end());
    s.min = v.front(), s.max = v.back();
    s.median = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
    s.spread = s.median != 0 ? (s.max - s.min) / s.median : 0.0;
    return s;
}

nlohmann::json toJson(const Summary& s) {
    return {{"median", s.median}, {"min", s.min}, {"max", s.max}, {"spread", s.spread}, {"values", s.values}};
}

std::string describeSummary(const Summary& s, int precision, const char* unit) {
    std::ostringstream o;
    o << std::fixed << std::setprecision(precision) << s.median << unit << " [" << s.min << "–" << s.max << ", "
      << std::setprecision(1) << 100.0 * s.spread << "%]";
    return o.str();
}

}  // namespace

int runBenchProcesses(const std::vector<std::string>& childArgs, int processes, double agreeWithin, bool json) {
    if (processes < 2) throw InputError("bench-accel: --processes needs at least 2");
    std::vector<nlohmann::json> runs;
    for (int p = 0; p < processes; ++p) {
        std::vector<std::string> argv{"/proc/self/exe"};
        argv.insert(argv.end(), childArgs.begin(), childArgs.end());
        std::string text = runCaptured(argv);
        try {
            runs.push_back(nlohmann::json::parse(text));
        } catch (const nlohmann::json::exception& e) {
            throw std::runtime_error(std::string("bench-accel --processes: unreadable report of a process: ") + e.what());
        }
        if (!json) std::cerr << "bench-accel: process " << p + 1 << " of " << processes << " done\n";
    }

    // Every figure of every process, keyed by input, structure and figure; ratios to Embree are
    // per process (Embree traced in the same process, interleaved), then summarised.
    const nlohmann::json& first = runs.front();
    nlohmann::json report = {{"processes", processes}, {"threads", first["threads"]}, {"repeat", first["repeat"]},
                             {"resolution", first["resolution"]}, {"clock", first["clock"]}, {"bvhConfig", first["bvhConfig"]},
                             {"kdConfig", first["kdConfig"]}, {"inputs", nlohmann::json::array()}};
    double worstSpread = 0.0;
    std::string worstWhat;
    if (!json)
        std::cout << "config: threads " << first["threads"] << ", repeat " << first["repeat"] << " per process, clock "
                  << first["clock"].get<std::string>() << ", " << processes
                  << " processes; each figure: median over processes [smallest–largest, (largest − smallest) / median]\n";
    for (size_t i = 0; i < first["inputs"].size(); ++i) {
        const nlohmann::json& in = first["inputs"][i];
        nlohmann::json entry = {{"input", in["input"]}, {"primitives", in["primitives"]}, {"rays", in["rays"]},
                                {"structures", nlohmann::json::object()}};
        if (!json) std::cout << in["input"].get<std::string>() << ": " << in["primitives"] << " primitives\n";
        for (auto it = in["structures"].begin(); it != in["structures"].end(); ++it) {
            const std::string name = it.key();
            std::vector<double> build, buildRatio;
            std::map<std::string, std::vector<double>> mrays, ratio;
            for (const nlohmann::json& run : runs) {
                const nlohmann::json& structures = run["inputs"][i]["structures"];
                const nlohmann::json& s = structures[name];
                build.push_back(s["buildSeconds"].get<double>());
                if (structures.contains("embree"))
                    buildRatio.push_back(s["buildSeconds"].get<double>() / structures["embree"]["buildSeconds"].get<double>());
                for (auto k = s["mraysPerSecond"].begin(); k != s["mraysPerSecond"].end(); ++k) mrays[k.key()].push_back(k.value());
                if (s.contains("ratioToEmbree"))
                    for (auto k = s["ratioToEmbree"].begin(); k != s["ratioToEmbree"].end(); ++k) ratio[k.key()].push_back(k.value());
            }
            nlohmann::json out = {{"buildSeconds", toJson(summarise(build))},
                                  {"bytesPerPrimitive", it.value()["bytesPerPrimitive"]}};
            std::ostringstream line;
            line << "  " << std::left << std::setw(8) << name << " build " << describeSummary(summarise(build), 3, " s");
            auto track = [&](const Summary& s, const std::string& what) {
                if (s.spread > worstSpread) worstSpread = s.spread, worstWhat = in["input"].get<std::string>() + ", " + name + ", " + what;
            };
            if (!buildRatio.empty() && name != "embree") {
                Summary s = summarise(buildRatio);
                out["buildRatioToEmbree"] = toJson(s);
                line << " = " << describeSummary(s, 2, "x") << " embree's";
                track(s, "build ratio");
            }
            for (const char* kind : {"primary", "diffuse", "shadow"}) {
                if (!mrays.count(kind)) continue;
                Summary s = summarise(mrays[kind]);
                out["mraysPerSecond"][kind] = toJson(s);
                line << "\n           " << std::setw(8) << kind << describeSummary(s, 2, " Mrays/s");
                if (ratio.count(kind) && name != "embree") {
                    Summary r = summarise(ratio[kind]);
                    out["ratioToEmbree"][kind] = toJson(r);
                    line << "  ratio " << describeSummary(r, 3, "x");
                    track(r, std::string(kind) + " ratio");
                }
            }
            entry["structures"][name] = out;
            if (!json) std::cout << line.str() << "\n";
        }
        report["inputs"].push_back(entry);
    }
    // The target the figures are for: every ratio to Embree agreeing across processes.
    report["largestRatioSpread"] = worstSpread;
    report["largestRatioSpreadAt"] = worstWhat;
    report["ratiosAgreeWithin"] = agreeWithin;
    report["ratiosAgree"] = worstSpread <= agreeWithin;
    if (json) std::cout << report.dump(2) << std::endl;
    else
        std::cout << "largest spread of a ratio to embree: " << std::fixed << std::setprecision(1) << 100.0 * worstSpread << "%"
                  << (worstWhat.empty() ? std::string() : " (" + worstWhat + ")") << "; all within "
                  << 100.0 * agreeWithin << "%: " << (worstSpread <= agreeWithin ? "yes" : "no") << "\n";
    return 0;
}

}  // namespace tessera::app
