// The subcommands of visvol. Each registers its options on the CLI11 app and
// returns the function that runs it once the arguments are parsed.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace visvol::cli {

using Runner = std::function<int()>;

Runner add_build_command(CLI::App& app);
Runner add_viewshed_command(CLI::App& app);
Runner add_info_command(CLI::App& app);
Runner add_verify_command(CLI::App& app);
Runner add_sample_command(CLI::App& app);
Runner add_export_command(CLI::App& app);
Runner add_plan_command(CLI::App& app);
Runner add_check_command(CLI::App& app);
Runner add_render_command(CLI::App& app);

}  // namespace visvol::cli
