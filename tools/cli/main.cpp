// The `tetrapage` command: thin subcommands over the libraries. Results go to stdout,
// logs and progress to stderr; every failure is one line on stderr and a non-zero exit.

#include <malloc.h>

#include <cstdio>
#include <exception>
#include <filesystem>
#include <new>
#include <string>

#include "Commands.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/TemporaryFiles.h"
#include "tetrapage/formats/index/IndexHeader.h"
#include "tetrapage/version.h"

namespace {

// Errors are one line on stderr (scripts read the last line): a message that spans lines
// (a library's, HDF5's) is joined with "; ".
std::string one_line(const char* message) {
  std::string text;
  for (const char* c = message; *c != 0; ++c) {
    if (*c == '\n' || *c == '\r') {
      while (!text.empty() && text.back() == ' ') text.pop_back();
      if (!text.empty() && text.back() != ';' && c[1] != 0 && c[1] != '\n') text += "; ";
    } else {
      text += *c;
    }
  }
  return text;
}

// The commands' --memory is a cap on resident memory, and glibc's malloc keeps what is freed
// by default: a heap per thread, and up to 32 MiB free at the top of each once its thresholds
// adapt. Blocks of 4 MiB and more mapped on their own (given back when freed) and two heaps took
// `fly --memory 64M` at 100M from the budget + 65 to + 60 MiB at the same steps per second, and
// a 2.9M-triangle preprocess from a 272 to a 225 MiB peak at the same time (docs/BENCHMARKS.md,
// "Memory held beside the shards at 100M"); one heap slowed the preprocess by 3 %.
void give_freed_memory_back() {
#if defined(__GLIBC__)
  constexpr int kReturnedBlockBytes = 4 << 20;
  mallopt(M_ARENA_MAX, 2);
  mallopt(M_MMAP_THRESHOLD, kReturnedBlockBytes);
  mallopt(M_TRIM_THRESHOLD, kReturnedBlockBytes);
#endif
}

}  // namespace

int main(int argc, char** argv) {
  give_freed_memory_back();
  CLI::App app{
      "tetrapage: out-of-core collision detection for huge CAD models.\n"
      "preprocess cuts meshes, STEP/IGES files and assemblies into an index on disk; fly pages it\n"
      "in around moving objects to answer collision, contact, distance and time-of-impact\n"
      "queries; inspect, validate, check-location, check-interiors and render examine an index;\n"
      "generate, mesh and replay make and read test scenes, objects and flights."};
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Show help for every subcommand");
  // The index format beside the release: indexes open only in a build of the same format.
  app.set_version_flag("--version", std::string("tetrapage ") + TETRAPAGE_VERSION_STRING +
                                        " (index format " +
                                        std::to_string(tetrapage::kIndexVersion) + ")");

  auto* generate = app.add_subcommand(
      "generate", "Generate the study's environments, flying objects and billiard flights");
  generate->require_subcommand(1);
  tetrapage::cli::add_generate_environment_commands(*generate);
  tetrapage::cli::add_generate_rack_command(*generate);
  tetrapage::cli::add_generate_flight_command(*generate);
  tetrapage::cli::add_replay_command(app);
  tetrapage::cli::add_mesh_commands(app);
  tetrapage::cli::add_index_commands(app);
  tetrapage::cli::add_fly_command(app);
  tetrapage::cli::add_interior_check_command(app);
  tetrapage::cli::add_check_location_command(app);
  tetrapage::cli::add_render_command(app);
  tetrapage::cli::refuse_empty_values(app);

  // Ctrl-C or a kill during a long command leaves no temporary file behind.
  tetrapage::remove_temporaries_on_signals();
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // CLI11 reports a misspelt command as a missing one: name the misspelling instead.
    const std::string unknown = tetrapage::cli::unknown_name_message(app, argc, argv);
    std::fprintf(stderr, "tetrapage: %s (see --help)\n",
                 unknown.empty() ? e.what() : unknown.c_str());
    return 2;
  } catch (const tetrapage::cli::UsageError& e) {
    std::fprintf(stderr, "tetrapage: %s (see --help)\n", one_line(e.what()).c_str());
    return 2;
  } catch (const tetrapage::Error& e) {
    std::fprintf(stderr, "tetrapage: %s\n", one_line(e.what()).c_str());
    return 1;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr,
                 "tetrapage: out of memory: the system refused an allocation (a smaller --memory, "
                 "fewer --threads or a smaller input may fit)\n");
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {
    // The path and the system's reason, without the library's "filesystem error:" wording.
    std::fprintf(stderr, "tetrapage: cannot use '%s': %s\n", e.path1().c_str(), e.code().message().c_str());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tetrapage: unexpected error: %s\n", one_line(e.what()).c_str());
    return 1;
  }
  return 0;
}
