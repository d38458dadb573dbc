#pragma once
// Each subcommand group registers itself on the app; main() only dispatches.
// A registration returns nothing; the callback it installs runs the command and throws
// tetrapage::Error (or CLI11 errors) on failure, which main() turns into one stderr line.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>

#include "tetrapage/tools/ReportFile.h"  // write_report, check_writable: every command uses them

namespace tetrapage::cli {

/// A CLI11 check that an option is a byte size (parse_byte_size: "64M", "1G", "1048576"), so
/// that a bad value is a command-line mistake (exit 2) found before any work.
CLI::Validator byte_size_check();
/// Adds `--memory SIZE` to `command`, defaulting to kDefaultMemoryBudget (ByteSize.h) in
/// `memory`: `purpose` says what it bounds, and the help adds the default and how sizes are
/// written, so that every command states both the same way.
CLI::Option* add_memory_option(CLI::App* command, std::string& memory, const std::string& purpose);
/// A CLI11 check that a whole number lies in [lowest, highest], with a message that names the
/// range as written (CLI11's own prints the type's limits).
CLI::Validator whole_number_check(long long lowest, long long highest);
/// A CLI11 check of an image size "WIDTHxHEIGHT", each 1 to 16384.
CLI::Validator image_size_check();

/// The parts a mesh file written from `parts` parts holds: all of them, or one where its
/// format holds none (STL, OFF), in which case one line on stdout says they were merged
/// (tools/cli/MeshCommands.cpp).
std::size_t parts_in_file(const std::filesystem::path& output, std::size_t parts);

/// `generate scene|tetras|terrain|object` (tools/cli/GenerateEnvironment.cpp)
void add_generate_environment_commands(CLI::App& generate);
/// `generate rack` (tools/cli/GenerateRack.cpp)
void add_generate_rack_command(CLI::App& generate);
/// `generate flight` (tools/cli/GenerateFlight.cpp)
void add_generate_flight_command(CLI::App& generate);
/// `replay` (tools/cli/ReplayCommand.cpp)
void add_replay_command(CLI::App& app);
/// `mesh info|convert` (tools/cli/MeshCommands.cpp)
void add_mesh_commands(CLI::App& app);
/// `preprocess`, `inspect`, `validate` (tools/cli/IndexCommands.cpp)
void add_index_commands(CLI::App& app);
/// `fly` (tools/cli/FlyCommand.cpp)
void add_fly_command(CLI::App& app);
/// `check-interiors` (tools/cli/InteriorCheckCommand.cpp)
void add_interior_check_command(CLI::App& app);
/// `check-location` (tools/cli/CheckLocationCommand.cpp)
void add_check_location_command(CLI::App& app);
/// `render` (tools/cli/RenderCommand.cpp)
void add_render_command(CLI::App& app);

}  // namespace tetrapage::cli
