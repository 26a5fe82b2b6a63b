/// \file main.cpp
/// `tessera COMMAND ...`: the command-line front end. Exit codes: 0 success, 1 a check failed
/// (e.g. validation), 2 bad input (scene, image or command line), 130 interrupted.
#include <iostream>

#include "app/commands.h"
#include "core/error.h"
#include "core/version.h"

int main(int argc, char** argv) {
    using namespace tessera;
    CLI::App app{"Tessera: a CPU path tracer whose images and numbers you can trust.\n"
                 "Renders glTF 2.0 scenes (plus Tessera's extensions) and measures error and speed.",
                 "tessera"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string("tessera ") + versionString() + " (" + gitRevision() + ")");
    app.footer("Run 'tessera COMMAND --help' for the options of a command.\n"
               "Example: tessera render scenes/cornell-box/cornell-box.gltf -o out/cornell-box.exr --spp 64");
    app::Runner render = app::addRenderCommand(app);
    app::Runner compare = app::addCompareCommand(app);
    app::Runner validateAccel = app::addValidateAccelCommand(app);
    app::Runner benchAccel = app::addBenchAccelCommand(app);
    app::Runner benchPhotons = app::addBenchPhotonsCommand(app);
    app::Runner view = app::addViewCommand(app);
    app::Runner merge = app::addMergeCommand(app);
    app::Runner farm = app::addFarmCommand(app);
    app::Runner batch = app::addBatchCommand(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;
    }
    try {
        if (app.got_subcommand("render")) return render();
        if (app.got_subcommand("compare")) return compare();
        if (app.got_subcommand("validate-accel")) return validateAccel();
        if (app.got_subcommand("bench-accel")) return benchAccel();
        if (app.got_subcommand("bench-photons")) return benchPhotons();
        if (app.got_subcommand("view")) return view();
        if (app.got_subcommand("merge")) return merge();
        if (app.got_subcommand("farm")) return farm();
        if (app.got_subcommand("batch")) return batch();
    } catch (const InputError& e) {
        app::printError(e.what());
        return 2;
    } catch (const std::exception& e) {
        app::printError(std::string("internal error: ") + e.what());
        return 3;
    }
    return 2;
}
