/// \file compare_command.cpp
/// `tessera compare TEST REF`: error statistics of an image against a reference.
#include <nlohmann/json.hpp>

#include <iostream>

#include "app/commands.h"
#include "io/image_compare.h"

namespace tessera::app {

Runner addCompareCommand(CLI::App& app) {
    struct Options {
        std::string test, ref;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand("compare", "Compare an image with a reference: means, RMSE, relMSE, max error");
    cmd->add_option("TEST", opt->test, "image to evaluate (EXR or any format OpenImageIO reads)")->required();
    cmd->add_option("REF", opt->ref, "reference image of the same resolution")->required();
    cmd->add_flag("--json", opt->json, "print one JSON object instead of text");
    cmd->footer("relMSE = mean over pixels and RGB of (x - r)^2 / (r^2 + 0.01). Pixels that are NaN/Inf in either\n"
                "image are counted and excluded from the error statistics.");
    return [opt] {
        io::CompareResult r = io::compareImages(opt->test, opt->ref);
        if (opt->json) std::cout << io::toJson(r).dump() << std::endl;
        else std::cout << io::toText(r);
        return 0;
    };
}

}  // namespace tessera::app
