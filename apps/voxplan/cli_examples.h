#pragma once
// The "Examples:" footer of every command's --help: commands as typed in the project root, on
// the shared data (../shared/data) or on what an earlier example wrote to out/.
#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace voxplan::cli {

// Sets the footer of each (sub)command that has examples; explore's also lists the planners it
// finds and where their options are described. Call once every command has been added.
void AddHelpExamples(CLI::App& app);

// The command paths ("fuse", "eval objects", ...) that have examples, with them (for tests).
std::vector<std::pair<std::string, std::vector<std::string>>> HelpExamples();

}  // namespace voxplan::cli
