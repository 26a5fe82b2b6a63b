/// \file merge_command.cpp
/// `tessera merge PARTS... -o OUT.exr`: joins sample-range partials (`render --samples A:B`) into
/// the image one render of all their samples would write, bit for bit (render/partial.h).
#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <optional>

#include "app/commands.h"
#include "core/error.h"
#include "core/version.h"
#include "io/display_transform.h"
#include "io/image_output.h"
#include "render/partial.h"
#include "render/progress.h"

namespace tessera::app {
namespace {

struct MergeArgs {
    std::vector<std::string> parts;
    std::string output, png, stderrImage, display = "sRGB", view = "Standard";
    bool allowGaps = false, noPng = false, quiet = false, json = false;
};

std::string setting(const CheckpointHeader& h, const std::string& key) {
    for (const auto& [k, v] : h)
        if (k == key) return v;
    return "";
}

/// The provenance `render` records (app/scene_options.h imageMetadata), from the partials' headers.
io::Metadata mergedMetadata(const MergedRender& m, size_t partCount) {
    const CheckpointHeader& h = m.settings;
    io::Metadata md = {
        {"Software", std::string("Tessera ") + versionString() + " (" + gitRevision() + ")"},
        {"tessera:version", versionString()},
        {"tessera:git", gitRevision()},
        {"tessera:scene", setting(h, "scene")},
        {"tessera:scene_hash", setting(h, "scene_hash")},
        {"tessera:integrator", setting(h, "integrator")},
        {"tessera:accel", setting(h, "accel")},
        {"tessera:spp", std::to_string(m.spp)},
        {"tessera:samples", std::to_string(m.samples)},
        {"tessera:seed", setting(h, "seed")},
        {"tessera:sampler", setting(h, "sampler")},
        {"tessera:max_depth", setting(h, "max_depth")},
        {"tessera:resolution", setting(h, "resolution")},
        {"tessera:render_seconds", std::to_string(m.seconds)},
        {"tessera:nonfinite_dropped", std::to_string(m.nonFinite)},
        {"tessera:interrupted", "false"},
        {"tessera:resumed", "false"},
        {"tessera:merged_partials", std::to_string(partCount)},
    };
    // An sppm render's photon settings (app/scene_options.h, photonSettings), as its parts recorded them.
    for (const auto& [key, value] : h)
        if (key.rfind("photon_", 0) == 0) md.push_back({"tessera:" + key, value});
    std::string ranges;
    for (const SampleRange& r : m.ranges) ranges += (ranges.empty() ? "" : ",") + r.str();
    md.push_back({"tessera:merged_samples", ranges});
    if (!m.gaps.empty()) {
        std::string gaps;
        for (const SampleRange& r : m.gaps) gaps += (gaps.empty() ? "" : ",") + r.str();
        md.push_back({"tessera:missing_samples", gaps});
    }
    if (m.firstNonFinite)
        md.push_back({"tessera:first_nonfinite", "pixel (" + std::to_string(m.firstNonFinite->x) + "," +
                                                     std::to_string(m.firstNonFinite->y) + ") sample " +
                                                     std::to_string(m.firstNonFinite->sample)});
    return md;
}

int runMerge(const MergeArgs& a) {
    const auto start = std::chrono::steady_clock::now();
    std::string png = a.noPng ? "" : (a.png.empty() ? std::filesystem::path(a.output).replace_extension(".png").string() : a.png);
    std::optional<io::DisplayTransform> display;
    if (!png.empty()) display.emplace(a.display, a.view);

    MergedRender m = mergePartials(a.parts, a.allowGaps);
    io::Metadata md = mergedMetadata(m, a.parts.size());
    const int w = m.film.width(), h = m.film.height();
    std::vector<float> rgba = m.film.rgba();
    io::writeExr(a.output, w, h, rgba.data(), md);
    if (display) io::writePng(png, w, h, rgba.data(), *display, md);
    if (!a.stderrImage.empty()) {
        std::vector<float> se = m.film.standardErrorRgba();
        io::Metadata sm = md;
        sm.push_back({"tessera:image", "standard error of the mean"});
        io::writeExr(a.stderrImage, w, h, se.data(), sm);
    }
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!m.gaps.empty()) printWarning("merged with missing samples " + setting(md, "tessera:missing_samples") + " (--allow-gaps)");
    if (!a.quiet)
        std::cerr << "tessera: merged " << a.parts.size() << " partials, " << m.spp << " spp, in " << formatDuration(seconds) << " -> "
                  << a.output << (png.empty() ? "" : ", " + png) << std::endl;
    if (a.json) {
        nlohmann::json ranges = nlohmann::json::array(), gaps = nlohmann::json::array();
        for (const SampleRange& r : m.ranges) ranges.push_back(r.str());
        for (const SampleRange& r : m.gaps) gaps.push_back(r.str());
        std::cout << nlohmann::json{{"output", a.output}, {"spp", m.spp}, {"samples", m.samples}, {"parts", a.parts.size()},
                                    {"ranges", ranges}, {"missing", gaps}, {"merge_seconds", seconds}}
                         .dump()
                  << std::endl;
    }
    return 0;
}

}  // namespace

Runner addMergeCommand(CLI::App& app) {
    auto a = std::make_shared<MergeArgs>();
    CLI::App* cmd = app.add_subcommand("merge", "Merge sample-range partials (render --samples A:B) into the final image");
    cmd->add_option("PARTS", a->parts, "partial files, in any order")->required();
    cmd->add_option("-o,--output", a->output, "output EXR")->required();
    cmd->add_option("--png", a->png, "also write a display-referred PNG here (default: the EXR path with .png)");
    cmd->add_flag("--no-png", a->noPng, "write only the EXR");
    cmd->add_option("--stderr-image", a->stderrImage, "also write the per-pixel standard error of the mean to this EXR");
    cmd->add_flag("--allow-gaps", a->allowGaps,
                  "merge even when sample ranges are missing; they are listed in the metadata (tessera:missing_samples)");
    cmd->add_option("--display", a->display, "OCIO display for the PNG (default: sRGB)");
    cmd->add_option("--view", a->view, "OCIO view for the PNG (default: Standard)");
    cmd->add_flag("--quiet", a->quiet, "no summary line");
    cmd->add_flag("--json", a->json, "print one JSON object with the merge's figures on stdout");
    cmd->footer("The merge of any split of samples 0:N is bit-identical to one render of N spp with the same seed.\n"
                "Refused (exit 2): overlapping or missing ranges, partials of different scenes or settings, corrupt files.");
    return [a] { return runMerge(*a); };
}

}  // namespace tessera::app
