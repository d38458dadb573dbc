#pragma once
// Each subcommand group registers itself on the app; main() only dispatches.
// A registration returns nothing; the callback it installs runs the command and throws
// tetrapage::Error (or CLI11 errors) on failure, which main() turns into one stderr line.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/tools/ReportFile.h"  // write_report, check_writable: every command uses them

namespace tetrapage::cli {

/// A command-line mistake found once the options are read (options that do not go together, an
/// option that would do nothing): main() reports it as it reports CLI11's own, with exit 2.
class UsageError : public InputError {
 public:
  using InputError::InputError;
};

/// Upper bounds of the options' ranges: the threads one machine may run, the points a check
/// draws (more would take hours), and a length in model units (coordinates beyond 1e300 are
/// refused in models and poses: their products would overflow).
inline constexpr long long kMostThreads = 1024;
inline constexpr long long kMostPoints = 100'000'000;
inline constexpr double kLongestLength = 1e300;

/// A CLI11 check that an option is a byte size (parse_byte_size: "64M", "1G", "1048576"), so
/// that a bad value is a command-line mistake (exit 2) found before any work.
/// Sizes below `minimum` bytes ("0", "1e-3", which rounds to 0) are refused too.
CLI::Validator byte_size_check(std::uint64_t minimum = 1);
/// Adds `--memory SIZE` to `command`, defaulting to kDefaultMemoryBudget (ByteSize.h) in
/// `memory`: `purpose` says what it bounds, and the help adds the default and how sizes are
/// written, so that every command states both the same way.
/// A budget below `minimum` bytes is a command-line mistake.
CLI::Option* add_memory_option(CLI::App* command, std::string& memory, const std::string& purpose,
                               std::uint64_t minimum = 1);
/// A CLI11 check that a whole number lies in [lowest, highest], with a message that names the
/// range as written (CLI11's own prints the type's limits).
CLI::Validator whole_number_check(long long lowest, long long highest);
/// A CLI11 check that an option is a finite number in [lowest, highest] ("nan", "inf" and
/// "1e999" are not); the help shows the range.
CLI::Validator number_check(double lowest, double highest);
/// A CLI11 check that an option is a finite number in (0, highest].
CLI::Validator positive_number_check(double highest);
/// A CLI11 check of a random seed: a whole number from 0 to 2^64-1, never a negative one that
/// would wrap around.
CLI::Validator seed_check();
/// A CLI11 check that `parse` (a library's reader of the option: parse_accuracy, metres_per_unit)
/// reads the option: the tetrapage::Error it throws becomes a command-line mistake with its
/// message. `name` is shown in the help as the value's kind.
CLI::Validator parsed_by(std::function<void(const std::string&)> parse, const std::string& name);
/// Makes an empty value ("--answers ''") a command-line mistake for every option that takes a
/// value, of `command` and of all its subcommands: no option means anything by an empty text.
void refuse_empty_values(CLI::App& command);
/// The first name on the command line `argv` that names no command or option of `app` (or of the
/// command it descends to), with the nearest known name when one is a slip away ("unknown
/// command 'instpect'; did you mean 'inspect'?"); empty when every name is known.
std::string unknown_name_message(CLI::App& app, int argc, const char* const* argv);
/// A CLI11 check that an input file exists and is not a folder, with the reason when it does
/// not: missing, a loop of symbolic links (ELOOP), no permission. (CLI11's ExistingFile says
/// "does not exist" for all of them.)
CLI::Validator existing_file_check();
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
