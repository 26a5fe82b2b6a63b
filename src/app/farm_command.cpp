/// \file farm_command.cpp
/// `tessera farm SCENE --parts K --spp N --out DIR [-- RENDER OPTIONS]`: renders on a Slurm cluster.
/// Writes DIR/render.sbatch, a job array with one task per sample range (`render --samples A:B`
/// into DIR/part_A-B.partial), and DIR/merge.sbatch (`tessera merge` of all parts into the image),
/// then submits the array and the merge with --dependency=afterok on it. Nothing but the tessera
/// binary runs on the nodes; DIR, the scene and the binary must be on a folder every node sees.
/// Re-running the same command submits only the ranges whose partial is not in DIR yet (partials
/// are written atomically: one that exists is complete). A failed task cancels the merge job
/// (--kill-on-invalid-dep=yes), so nothing is left waiting.
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "app/commands.h"
#include "app/scene_options.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "render/partial.h"

namespace tessera::app {
namespace {

namespace fs = std::filesystem;

struct FarmArgs {
    std::string scene, out, output, tessera, sbatch = "sbatch", jobName;
    int parts = 0, spp = 0, cpusPerTask = 0;
    std::vector<std::string> renderArgs, sbatchArgs;
    bool dryRun = false, json = false;
};

/// Single-quoted for bash: every byte literal.
std::string quoted(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

/// The K ranges of [0, N): range k is [floor(kN/K), floor((k+1)N/K)), so lengths differ by at most 1.
std::vector<SampleRange> splitSamples(int spp, int parts) {
    std::vector<SampleRange> r;
    for (int k = 0; k < parts; ++k)
        r.push_back({uint32_t(int64_t(k) * spp / parts), uint32_t(int64_t(k + 1) * spp / parts)});
    return r;
}

std::string partPath(const std::string& dir, const SampleRange& r) {
    return dir + "/part_" + std::to_string(r.begin) + "-" + std::to_string(r.end) + ".partial";
}

/// True when `path` holds a partial of samples `r` (a complete file: partials are written atomically;
/// its settings are checked by the merge).
bool partialDone(const std::string& path, const SampleRange& r) {
    if (!fs::exists(path)) return false;
    try {
        for (const auto& [k, v] : readCheckpointHeader(path))
            if (k == "samples") return v == r.str();
    } catch (const InputError&) {
    }
    return false;
}

std::string sbatchHeader(const FarmArgs& a, const std::string& name, const std::string& log) {
    std::string s = "#!/bin/bash\n#SBATCH --job-name=" + name + "\n#SBATCH --output=" + log + "\n";
    if (a.cpusPerTask > 0) s += "#SBATCH --cpus-per-task=" + std::to_string(a.cpusPerTask) + "\n";
    for (const std::string& arg : a.sbatchArgs) s += "#SBATCH " + arg + "\n";
    return s + "set -euo pipefail\n";
}

std::string renderScript(const FarmArgs& a, const std::vector<SampleRange>& ranges, const std::vector<size_t>& todo) {
    std::string indices;
    for (size_t k : todo) indices += (indices.empty() ? "" : ",") + std::to_string(k);
    std::string s = sbatchHeader(a, a.jobName, a.out + "/logs/render_%A_%a.out");
    s.insert(s.find("#SBATCH --output"), "#SBATCH --array=" + indices + "\n");
    s += "RANGES=(";
    for (const SampleRange& r : ranges) s += " " + r.str();
    s += " )\nPARTS=(";
    for (const SampleRange& r : ranges) s += " " + quoted(partPath(a.out, r));
    s += " )\nexec " + quoted(a.tessera) + " render " + quoted(a.scene) + " --spp " + std::to_string(a.spp) +
         " --samples \"${RANGES[$SLURM_ARRAY_TASK_ID]}\" -o \"${PARTS[$SLURM_ARRAY_TASK_ID]}\" --quiet";
    if (a.cpusPerTask > 0) s += " --threads " + std::to_string(a.cpusPerTask);
    for (const std::string& arg : a.renderArgs) s += " " + quoted(arg);
    return s + "\n";
}

std::string mergeScript(const FarmArgs& a, const std::vector<SampleRange>& ranges) {
    std::string s = sbatchHeader(a, a.jobName + "-merge", a.out + "/logs/merge_%j.out");
    s += "exec " + quoted(a.tessera) + " merge";
    for (const SampleRange& r : ranges) s += " " + quoted(partPath(a.out, r));
    return s + " -o " + quoted(a.output) + " --stderr-image " + quoted(fs::path(a.output).replace_extension("").string() + "_stderr.exr") +
           "\n";
}

/// Runs `sbatch --parsable ARGS SCRIPT` and returns the job id it prints ("id" or "id;cluster").
std::string submit(const FarmArgs& a, const std::string& extra, const std::string& script) {
    std::string cmd = quoted(a.sbatch) + " --parsable " + extra + " " + quoted(script) + " 2>&1";
    std::unique_ptr<FILE, int (*)(FILE*)> p(popen(cmd.c_str(), "r"), pclose);
    if (!p) throw InputError("farm: cannot run " + a.sbatch);
    std::string out;
    char buf[512];
    while (std::fgets(buf, sizeof buf, p.get())) out += buf;
    int status = pclose(p.release());
    while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
    std::string id = out.substr(0, out.find(';'));
    if (status != 0 || id.empty() || id.find_first_not_of("0123456789") != std::string::npos)
        throw InputError("farm: sbatch " + script + " failed: " + out);
    return id;
}

void writeText(const std::string& path, const std::string& text) {
    writeFileAtomically(path, "script", [&](const std::string& tmp) {
        std::ofstream f(tmp);
        f << text;
        if (!f.flush()) throw InputError(path + ": cannot write");
    });
}

int runFarm(FarmArgs a) {
    if (a.parts < 1 || a.spp < a.parts)
        throw InputError("farm: --parts " + std::to_string(a.parts) + " needs 1 <= parts <= --spp (" + std::to_string(a.spp) + ")");
    for (const std::string& arg : a.renderArgs)
        for (const char* owned : {"--samples", "-o", "--output", "--spp", "--time", "--checkpoint", "--resume", "--threads"})
            if (arg == owned || arg.rfind(std::string(owned) + "=", 0) == 0)
                throw InputError(std::string("farm: ") + owned + " is the farm's to set; leave it out of the render options");
    if (!fs::exists(a.scene)) throw InputError(a.scene + ": no such scene");
    a.scene = fs::absolute(a.scene).lexically_normal().string();
    a.out = fs::absolute(a.out).lexically_normal().string();
    while (a.out.size() > 1 && a.out.back() == '/') a.out.pop_back();
    a.output = a.output.empty() ? a.out + "/" + stem(a.scene) + ".exr" : fs::absolute(a.output).lexically_normal().string();
    if (a.tessera.empty()) a.tessera = fs::read_symlink("/proc/self/exe").string();
    if (a.jobName.empty()) a.jobName = "tessera-" + stem(a.scene);

    std::vector<SampleRange> ranges = splitSamples(a.spp, a.parts);
    std::vector<size_t> todo;
    for (size_t k = 0; k < ranges.size(); ++k)
        if (!partialDone(partPath(a.out, ranges[k]), ranges[k])) todo.push_back(k);
    std::string render = renderScript(a, ranges, todo), merge = mergeScript(a, ranges);
    if (a.dryRun) {
        if (!todo.empty()) std::cout << "# " << a.out << "/render.sbatch\n" << render << "\n";
        std::cout << "# " << a.out << "/merge.sbatch (--dependency=afterok:<render array>)\n" << merge;
        return 0;
    }
    fs::create_directories(a.out + "/logs");
    writeText(a.out + "/render.sbatch", render);
    writeText(a.out + "/merge.sbatch", merge);
    std::string arrayId = todo.empty() ? "" : submit(a, "", a.out + "/render.sbatch");
    // A failed task cancels the merge (instead of leaving it pending forever); the re-run submits anew.
    std::string mergeId =
        submit(a, arrayId.empty() ? "" : "--dependency=afterok:" + arrayId + " --kill-on-invalid-dep=yes", a.out + "/merge.sbatch");
    if (a.json) {
        nlohmann::json submitted = nlohmann::json::array();
        for (size_t k : todo) submitted.push_back(ranges[k].str());
        std::cout << nlohmann::json{{"array_job", arrayId}, {"merge_job", mergeId}, {"submitted", submitted},
                                    {"kept", ranges.size() - todo.size()}, {"output", a.output}}
                         .dump()
                  << std::endl;
    } else {
        std::cout << "tessera farm: " << todo.size() << " of " << ranges.size() << " ranges submitted"
                  << (arrayId.empty() ? "" : " as array job " + arrayId) << " (" << ranges.size() - todo.size()
                  << " already done); merge job " << mergeId << " -> " << a.output << std::endl;
    }
    return 0;
}

}  // namespace

Runner addFarmCommand(CLI::App& app) {
    auto a = std::make_shared<FarmArgs>();
    CLI::App* cmd = app.add_subcommand("farm", "Render on a Slurm cluster: a job array of sample ranges, then a merge job");
    cmd->add_option("SCENE", a->scene, "scene file (on a folder every node sees)")->required();
    cmd->add_option("RENDER_OPTIONS", a->renderArgs, "after --: options passed to every 'tessera render' (e.g. -- --integrator bdpt)");
    cmd->add_option("--parts", a->parts, "number of sample ranges (array tasks)")->required()->check(CLI::Range(1, 100000));
    cmd->add_option("--spp", a->spp, "total samples per pixel")->required()->check(CLI::Range(1, 1 << 30));
    cmd->add_option("--out", a->out, "shared folder for the scripts, partials, logs and the image")->required();
    cmd->add_option("-o,--output", a->output, "merged EXR (default: OUT/<scene>.exr; also a PNG and OUT/<scene>_stderr.exr)");
    cmd->add_option("--cpus-per-task", a->cpusPerTask, "CPUs each array task asks for (and renders with)")->check(CLI::Range(1, 4096));
    cmd->add_option("--sbatch-arg", a->sbatchArgs, "an extra #SBATCH line for both scripts, e.g. --sbatch-arg=--partition=gpu (repeatable)");
    cmd->add_option("--job-name", a->jobName, "Slurm job name (default: tessera-<scene>)");
    cmd->add_option("--tessera", a->tessera, "the tessera binary the nodes run (default: this one)");
    cmd->add_option("--sbatch", a->sbatch, "the sbatch command (default: sbatch on PATH)");
    cmd->add_flag("--dry-run", a->dryRun, "print the scripts, submit nothing");
    cmd->add_flag("--json", a->json, "print the job ids as one JSON object");
    cmd->footer("Example: tessera farm scene.gltf --parts 16 --spp 4096 --out /shared/run1 -- --integrator bdpt --seed 7\n"
                "Re-run the same command after a failure: only the ranges without a partial are submitted again.");
    return [a] { return runFarm(*a); };
}

}  // namespace tessera::app
