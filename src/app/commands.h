#pragma once
/// \file commands.h
/// The `tessera` subcommands. Each registers its options on the CLI11 app and returns a runner
/// called after parsing; runners return the process exit code.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace tessera::app {

using Runner = std::function<int()>;

Runner addRenderCommand(CLI::App& app);
Runner addCompareCommand(CLI::App& app);
Runner addValidateAccelCommand(CLI::App& app);
Runner addBenchAccelCommand(CLI::App& app);
Runner addBenchPhotonsCommand(CLI::App& app);
Runner addViewCommand(CLI::App& app);
Runner addMergeCommand(CLI::App& app);
Runner addFarmCommand(CLI::App& app);
Runner addBatchCommand(CLI::App& app);

/// "a, b, c": the names an option accepts, for its help text.
std::string commaSeparated(const std::vector<std::string>& names);
/// Prints "tessera: error: MESSAGE" on one line to stderr.
void printError(const std::string& message);
void printWarning(const std::string& message);

}  // namespace tessera::app
