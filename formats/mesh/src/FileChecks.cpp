#include "tetrapage/formats/mesh/FileChecks.h"

#include <sys/stat.h>

#include <algorithm>
#include <cstring>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/Manifest.h"

namespace tetrapage {
namespace {

std::string kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// Whether two existing paths name the same file.
bool same_file(const struct stat& a, const struct stat& b) { return a.st_dev == b.st_dev && a.st_ino == b.st_ino; }

// 'path', for a message.
std::string quoted_path(const std::filesystem::path& path) {
  std::string text(1, '\'');
  text.append(path.string());
  text.push_back('\'');
  return text;
}

// A file a command reads, and the input that makes it read it.
struct ReadFile {
  std::filesystem::path file, input;
};

// Every file reading `inputs` opens (files_read_from), listed once per check.
std::vector<ReadFile> files_read(std::span<const std::filesystem::path> inputs) {
  std::vector<ReadFile> read;
  for (const auto& input : inputs)
    for (auto& file : files_read_from(input)) read.push_back({std::move(file), input});
  return read;
}

// What the output would destroy among the files read: "the input 'a.ply'", or "'part.ply',
// which the input 'a.json' reads"; empty when none.
std::string input_destroyed(const struct stat& output, const std::vector<ReadFile>& read) {
  for (const auto& [file, input] : read) {
    struct stat other {};
    if (::stat(file.c_str(), &other) != 0 || !same_file(output, other)) continue;
    // Appended piece by piece: GCC 12 warns (-Wrestrict) on "literal" + string here.
    std::string what(file == input ? "the input " : "");
    if (file != input) what.append(quoted_path(file)).append(", which the input ");
    what.append(quoted_path(input));
    if (file != input) what.append(" reads");
    return what;
  }
  return {};
}

// Whether `name` is one of the part files a manifest writer puts in its folder.
bool is_part_file_name(const std::string& name) {
  return name.size() == 15 && name.rfind("part-", 0) == 0 && name.ends_with(".ply") &&
         name.find_first_not_of("0123456789", 5) == 11;
}

// The part folder is replaced whole: only when it holds nothing but part files (what an earlier
// conversion wrote), so that no file of the user's is lost.
void require_own_part_folder(const std::filesystem::path& output,
                             const std::filesystem::path& folder) {
  std::error_code error;
  const auto status = std::filesystem::symlink_status(folder, error);
  if (!std::filesystem::exists(status)) return;
  const std::string refusal =
      "refusing to write '" + output.string() + "': its part folder '" + folder.string() + "' ";
  if (!std::filesystem::is_directory(status))
    throw InputError(refusal + "exists and is not a folder");
  for (const auto& entry : std::filesystem::directory_iterator(folder, error)) {
    const std::string name = entry.path().filename().string();
    if (!is_part_file_name(name) || entry.is_symlink(error) || !entry.is_regular_file(error))
      throw InputError(refusal + "holds '" + name + "', which tetrapage did not write");
  }
}

// A manifest output replaces the folder of part files beside it (MeshWriter.h): it must be its
// own, and no file read may live there.
void check_part_folder(const std::filesystem::path& output, const std::vector<ReadFile>& read) {
  require_own_part_folder(output, output.parent_path() / (output.stem().string() + ".parts"));
  std::error_code error;
  const std::filesystem::path folder =
      std::filesystem::weakly_canonical(output.parent_path() / (output.stem().string() + ".parts"), error);
  if (error) return;
  for (const auto& [file, input] : read) {
    const std::filesystem::path path = std::filesystem::weakly_canonical(file, error);
    if (error) continue;
    const auto [end, ignored] = std::mismatch(folder.begin(), folder.end(), path.begin(), path.end());
    if (end == folder.end())
      throw InputError("refusing to write '" + output.string() + "': it replaces the folder '" + folder.string() +
                       "', which holds '" + file.string() + "' that the input '" + input.string() + "' reads");
  }
}

}  // namespace

void require_regular_file(const std::filesystem::path& path) {
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) return;  // opening it says why
  if (!S_ISREG(status.st_mode))
    throw IoError("cannot read '" + path.string() + "': it is " + kind_of(status.st_mode) + ", not a regular file");
}

void check_outputs(std::span<const std::filesystem::path> outputs, std::span<const std::filesystem::path> inputs) {
  const std::vector<ReadFile> read = files_read(inputs);  // manifests parsed once, not per output
  for (const std::filesystem::path& output : outputs) {
    if (output.empty()) continue;
    if (is_manifest_path(output)) check_part_folder(output, read);
    struct stat status {};
    if (::stat(output.c_str(), &status) != 0) continue;  // a new file: nothing to destroy
    if (!S_ISREG(status.st_mode))
      throw InputError("refusing to write '" + output.string() + "': it is " + kind_of(status.st_mode) +
                       ", not a regular file");
    if (const std::string destroyed = input_destroyed(status, read); !destroyed.empty())
      throw InputError("refusing to write '" + output.string() + "': it is " + destroyed);
  }
  // Two outputs naming one file, existing or not.
  for (std::size_t i = 0; i < outputs.size(); ++i)
    for (std::size_t j = 0; j < i; ++j) {
      if (outputs[i].empty() || outputs[j].empty()) continue;
      std::error_code ignored;
      if (std::filesystem::weakly_canonical(outputs[i], ignored) == std::filesystem::weakly_canonical(outputs[j], ignored))
        throw InputError("refusing to write '" + outputs[i].string() + "' twice (it is also '" + outputs[j].string() + "')");
    }
}

}  // namespace tetrapage
