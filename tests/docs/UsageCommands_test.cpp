// The command lines of docs/USAGE.md and README.md name real commands and real options: every
// `tetrapage ...` line of a ```sh or ```bash block, and every inline `code` span that starts
// with `tetrapage` or with one of its commands, is checked against that command's --help. The
// ```c and ```cpp blocks are compiled and run by the docs_usage_example_* tests instead
// (CMakeLists.txt).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

// One command line found in a document: where, and its words after `tetrapage`.
struct CommandLine {
  std::string where;
  std::vector<std::string> words;
};

std::string run_help(const std::string& command) {
  const std::string line = std::string(TETRAPAGE_CLI) + " " + command + " --help 2>&1";
  FILE* pipe = popen(line.c_str(), "r");
  std::string out;
  if (!pipe) return out;
  char buffer[4096];
  while (std::size_t n = fread(buffer, 1, sizeof buffer, pipe)) out.append(buffer, n);
  const int status = pclose(pipe);
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? out : std::string();
}

// A command's help, parsed: its options (long and short) and its subcommands.
struct Help {
  bool exists = false;
  std::set<std::string> options, subcommands;
};

Help parse_help(const std::string& text) {
  Help help;
  help.exists = !text.empty();
  std::istringstream lines(text);
  bool in_subcommands = false;
  for (std::string line; std::getline(lines, line);) {
    if (line == "Subcommands:") {
      in_subcommands = true;
      continue;
    }
    const std::size_t start = line.find_first_not_of(' ');
    if (start == std::string::npos) continue;
    if (start == 0) in_subcommands = false;
    // "  -o,--output TEXT REQUIRED": the names before the first space.
    if (line[start] == '-') {
      std::stringstream names(line.substr(start, line.find(' ', start) - start));
      for (std::string name; std::getline(names, name, ',');) help.options.insert(name);
    } else if (in_subcommands && start == 2) {
      help.subcommands.insert(line.substr(2, line.find(' ', 2) - 2));
    }
  }
  return help;
}

class Commands {
 public:
  const Help& help(const std::string& command) {
    auto found = helps_.find(command);
    if (found == helps_.end()) found = helps_.emplace(command, parse_help(run_help(command))).first;
    return found->second;
  }

  // What is wrong with `words` (empty when nothing is).
  std::string check(const std::vector<std::string>& words) {
    std::string command;
    std::size_t i = 0;
    // The command path: as long as the current command has subcommands, the next word is one.
    for (; i < words.size() && !help(command).subcommands.empty(); ++i) {
      if (words[i].starts_with("-")) break;
      if (!help(command).subcommands.contains(words[i]))
        return "'" + words[i] + "' is not a command of `tetrapage" +
               (command.empty() ? "" : " " + command) + "`";
      command += (command.empty() ? "" : " ") + words[i];
    }
    if (command.empty()) return "no command";
    const Help& options = help(command);
    if (!options.exists) return "`tetrapage " + command + " --help` fails";
    std::string problems;
    for (; i < words.size(); ++i) {
      const std::string option = option_name(words[i]);
      if (!option.empty() && !options.options.contains(option))
        problems += (problems.empty() ? "" : "; ") + std::string("`tetrapage ") + command +
                    "` has no option " + option;
    }
    return problems;
  }

  // "--memory" of "[--memory", "--accuracy=exact", "-o"; empty for anything else ("-5x3", "FILE").
  static std::string option_name(std::string word) {
    while (!word.empty() && (word.front() == '[' || word.front() == '(')) word.erase(0, 1);
    while (!word.empty() && std::string("]),.;").find(word.back()) != std::string::npos)
      word.pop_back();
    if (const std::size_t equals = word.find('='); equals != std::string::npos) word.resize(equals);
    if (word.size() == 2 && word[0] == '-' && std::isalpha(static_cast<unsigned char>(word[1])))
      return word;
    if (word.size() > 2 && word.starts_with("--") &&
        std::isalpha(static_cast<unsigned char>(word[2]))) {
      for (const char c : word)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-') return {};
      return word;
    }
    return {};
  }

 private:
  std::map<std::string, Help> helps_;
};

std::vector<std::string> split_words(const std::string& text) {
  std::vector<std::string> words;
  std::istringstream in(text);
  for (std::string word; in >> word;) words.push_back(word);
  return words;
}

// A shell line without its comment: from a '#' at the start or after a blank, outside quotes.
std::string without_comment(const std::string& line) {
  char quote = 0;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '\'' || c == '"') {
      quote = c;
    } else if (c == '#' && (i == 0 || line[i - 1] == ' ' || line[i - 1] == '\t')) {
      return line.substr(0, i);
    }
  }
  return line;
}

// The `tetrapage` commands of one shell line: its words split at &&, ||, | and ;.
void shell_commands(const std::string& line, const std::string& where,
                    std::vector<CommandLine>& found) {
  std::vector<std::vector<std::string>> segments(1);
  for (std::string word : split_words(without_comment(line))) {
    if (word == "&&" || word == "||" || word == "|" || word == ";") {
      segments.emplace_back();
      continue;
    }
    const bool ends = word.size() > 1 && word.back() == ';';
    if (ends) word.pop_back();
    segments.back().push_back(word);
    if (ends) segments.emplace_back();
  }
  for (const auto& segment : segments)
    if (segment.size() > 1 && segment.front() == "tetrapage")
      found.push_back({where, std::vector<std::string>(segment.begin() + 1, segment.end())});
}

// Every command line of a Markdown file: shell blocks line by line (continuations joined,
// here-documents skipped), and inline code spans outside blocks that start with `tetrapage`
// or with a command of it. A closing fence with text after it (which Markdown renders as
// part of the block) is added to `problems`.
std::vector<CommandLine> command_lines(const std::string& path, const std::string& name,
                                       Commands& commands, std::string& problems) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  std::vector<CommandLine> found;
  std::string fence, logical, heredoc, prose;
  int line_number = 0, logical_start = 0, prose_start = 0;
  const auto flush_prose = [&] {
    // Inline spans: `...` pairs, which may run over a line break.
    for (std::size_t open = prose.find('`'); open != std::string::npos;) {
      const std::size_t close = prose.find('`', open + 1);
      if (close == std::string::npos) break;
      std::vector<std::string> words = split_words(prose.substr(open + 1, close - open - 1));
      const int line =
          prose_start + int(std::count(prose.begin(), prose.begin() + std::ptrdiff_t(open), '\n'));
      if (!words.empty() && words.front() == "tetrapage") words.erase(words.begin());
      if (!words.empty() && commands.help("").subcommands.contains(words.front()))
        found.push_back({name + ":" + std::to_string(line), words});
      open = prose.find('`', close + 1);
    }
    prose.clear();
  };
  for (std::string line; std::getline(in, line);) {
    ++line_number;
    if (line.starts_with("```")) {
      if (fence.empty()) {
        flush_prose();
        fence = line.size() > 3 ? line.substr(3) : "text";
      } else {
        if (line != "```")
          problems += name + ":" + std::to_string(line_number) +
                      ": text after the closing fence: " + line + "\n";
        fence.clear();
        prose_start = line_number + 1;
      }
      continue;
    }
    if (fence.empty()) {
      if (prose.empty()) prose_start = line_number;
      prose += line + "\n";
      if (line.empty()) flush_prose();  // spans do not cross paragraphs
      continue;
    }
    if (fence != "sh" && fence != "bash") continue;
    if (!heredoc.empty()) {
      if (line == heredoc) heredoc.clear();
      continue;
    }
    if (logical.empty()) logical_start = line_number;
    if (line.ends_with("\\")) {
      logical += line.substr(0, line.size() - 1) + " ";
      continue;
    }
    logical += line;
    if (const std::size_t here = logical.find("<<"); here != std::string::npos) {
      std::string marker = split_words(logical.substr(here + 2)).at(0);
      std::erase(marker, '\'');
      std::erase(marker, '"');
      heredoc = marker;
    }
    shell_commands(logical, name + ":" + std::to_string(logical_start), found);
    logical.clear();
  }
  flush_prose();
  return found;
}

TEST(UsageCommands, NameRealCommandsAndOptions) {
  Commands commands;
  ASSERT_TRUE(commands.help("").subcommands.contains("fly")) << "cannot read `tetrapage --help`";
  std::size_t checked = 0;
  std::string problems;
  for (const char* document : {"docs/USAGE.md", "README.md"}) {
    for (const CommandLine& line : command_lines(std::string(TETRAPAGE_SOURCE_DIR) + "/" + document,
                                                 document, commands, problems)) {
      ++checked;
      std::string text;
      for (const std::string& word : line.words) text += " " + word;
      if (const std::string problem = commands.check(line.words); !problem.empty())
        problems += line.where + ": `tetrapage" + text + "`: " + problem + "\n";
    }
  }
  EXPECT_TRUE(problems.empty()) << problems;
  // The documents hold many (a parser that found none would pass vacuously).
  EXPECT_GT(checked, 100u);
}

// The parser itself, on lines whose answer is known.
TEST(UsageCommands, TheCheckFindsWrongNames) {
  Commands commands;
  EXPECT_EQ(commands.check(
                {"fly", "m.tpi", "--object", "o.ply", "--path", "f.csv", "[--memory", "SIZE]"}),
            "");
  EXPECT_EQ(commands.check({"render", "m.tpi", "--size", "-5x3", "-o", "x.png"}), "");
  EXPECT_NE(commands.check({"fly", "m.tpi", "--budget", "1G"}).find("no option --budget"),
            std::string::npos);
  EXPECT_NE(commands.check({"generate", "scenery"}).find("'scenery' is not a command"),
            std::string::npos);
  EXPECT_NE(commands.check({"flyy"}).find("'flyy' is not a command"), std::string::npos);
  EXPECT_EQ(Commands::option_name("--accuracy=exact"), "--accuracy");
  EXPECT_EQ(Commands::option_name("-5x3"), "");
  std::vector<CommandLine> found;
  shell_commands(
      "tetrapage mesh convert a.obj -o a.ply && tetrapage mesh info a.ply  # --not-an-option", "x",
      found);
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[1].words, (std::vector<std::string>{"mesh", "info", "a.ply"}));
}

}  // namespace
