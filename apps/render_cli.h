// The `gradel render` subcommand's command-line options (CLI11), kept in the program: the
// library's gradel::render::runRenderCommand takes the filled RenderCommandOptions.
#pragma once

#include <CLI/CLI.hpp>

#include "gradel/render/render_command.h"

namespace gradel::render {

/// Adds the `render` subcommand to the CLI, filling `o`.
CLI::App* addRenderCommand(CLI::App& app, RenderCommandOptions& o);

}  // namespace gradel::render
