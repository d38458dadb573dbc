// Names on a command line that no command or option holds, with the nearest known one: CLI11
// reports a misspelt command as a missing one and a misspelt required option as absent.

#include <algorithm>
#include <cctype>
#include <string>
#include <utility>
#include <vector>

#include "Commands.h"

namespace tetrapage::cli {
namespace {

// Edits (insert, delete, replace, swap two neighbours) that turn `typed` into `known`.
std::size_t edit_distance(const std::string& typed, const std::string& known) {
  const std::size_t rows = typed.size() + 1, columns = known.size() + 1;
  std::vector<std::size_t> cost(rows * columns);
  auto at = [&](std::size_t i, std::size_t j) -> std::size_t& { return cost[i * columns + j]; };
  for (std::size_t i = 0; i < rows; ++i) at(i, 0) = i;
  for (std::size_t j = 0; j < columns; ++j) at(0, j) = j;
  for (std::size_t i = 1; i < rows; ++i)
    for (std::size_t j = 1; j < columns; ++j) {
      const std::size_t replace = at(i - 1, j - 1) + (typed[i - 1] == known[j - 1] ? 0 : 1);
      at(i, j) = std::min({at(i - 1, j) + 1, at(i, j - 1) + 1, replace});
      if (i > 1 && j > 1 && typed[i - 1] == known[j - 2] && typed[i - 2] == known[j - 1])
        at(i, j) = std::min(at(i, j), at(i - 2, j - 2) + 1);
    }
  return at(rows - 1, columns - 1);
}

// The known name nearest `typed`, when near enough to be what was meant (a slip of a key or
// two, or the start of the name); else empty.
std::string nearest_name(const std::string& typed, const std::vector<std::string>& known) {
  std::string best;
  std::size_t best_distance = 3;  // more edits than two: another word, not a slip
  for (const std::string& name : known) {
    std::size_t distance = edit_distance(typed, name);
    if (typed.size() >= 4 && name.starts_with(typed)) distance = std::min<std::size_t>(distance, 1);
    if (distance < best_distance && distance < name.size() / 2 + 1) {
      best = name;
      best_distance = distance;
    }
  }
  return best;
}

// "unknown option '--obect' of fly; did you mean '--object'?", or the known names when none is
// near.
std::string with_suggestion(const std::string& what, const std::string& typed,
                            const std::string& where, const std::vector<std::string>& known) {
  const std::string nearest = nearest_name(typed, known);
  std::string message = "unknown " + what + " '" + typed + "'" + where;
  if (!nearest.empty()) return message + "; did you mean '" + nearest + "'?";
  std::string list;
  for (const std::string& name : known) list += (list.empty() ? "" : ", ") + name;
  return message + " (" + list + ")";
}

std::vector<std::string> command_names(CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* command : app.get_subcommands([](CLI::App*) { return true; }))
    names.push_back(command->get_name());
  return names;
}

std::vector<std::string> option_names(CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::Option* option : app.get_options()) {
    for (const std::string& name : option->get_lnames()) names.push_back("--" + name);
    for (const std::string& name : option->get_snames()) names.push_back("-" + name);
  }
  return names;
}

// The option name `token` spells ("--object" of "--object=a.ply", "-o"), or empty when it is a
// value: a positional, a negative number.
std::string option_name(const std::string& token) {
  if (token.starts_with("--") && token.size() > 2) return token.substr(0, token.find('='));
  if (token.size() >= 2 && token[0] == '-' && std::isalpha(static_cast<unsigned char>(token[1])))
    return token.substr(0, 2);
  return {};
}

}  // namespace

std::string unknown_name_message(CLI::App& app, int argc, const char* const* argv) {
  CLI::App* current = &app;
  bool value_next = false;  // the token after an option that takes a value is its value ("-inf")
  for (int i = 1; i < argc; ++i) {
    const std::string token = argv[i];
    if (token == "--") break;
    if (std::exchange(value_next, false)) continue;
    const std::string name = option_name(token);
    if (!name.empty()) {
      const CLI::Option* option = current->get_option_no_throw(name);
      value_next = option != nullptr && option->get_type_size() > 0 &&
                   token.find('=') == std::string::npos;
      if (option == nullptr)
        return with_suggestion("option", name, current == &app ? "" : " of " + current->get_name(),
                               option_names(*current));
      continue;
    }
    // A command that takes commands (tetrapage, generate, mesh) takes nothing else.
    const std::vector<std::string> commands = command_names(*current);
    if (commands.empty()) continue;
    if (std::find(commands.begin(), commands.end(), token) == commands.end())
      return with_suggestion("command", token, "", commands);
    current = current->get_subcommand(token);
  }
  return {};
}

}  // namespace tetrapage::cli
