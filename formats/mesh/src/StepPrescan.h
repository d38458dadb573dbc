#pragma once
// A light pass over a STEP file's entity instances (ISO 10303-21) before OpenCASCADE reads it:
// OCCT's reader follows assembly relations recursively, so a cyclic or very deep assembly
// overflows its stack. The scan keeps only the relations it follows, never the file.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace tetrapage::detail {

/// Assemblies nested deeper than this are refused, by the pre-scan and by the assembly walk.
inline constexpr int kMaxAssemblyDepth = 256;

/// What the scan found: the longest chain and the first cycle of each kind of relation.
struct StepStructure {
  std::uint64_t instances = 0;             ///< entity instances (#n = ...)
  std::uint64_t assembly_occurrences = 0;  ///< product usages (NEXT_ASSEMBLY_USAGE_OCCURRENCE...)
  int assembly_depth = 0;                  ///< product definitions nested, longest chain
  int representation_depth = 0;            ///< representations related, longest chain
  int mapped_item_depth = 0;               ///< representations mapped into others, longest chain
  std::string cycle;                       ///< "product definitions #1 -> #2 -> #1"; empty if none
};

/// Incremental scanner: feed the bytes in pieces of any size, then finish(). Any bytes are
/// accepted (what is not an entity instance is skipped); memory grows with the relations
/// kept, never with the text.
class StepScanner {
 public:
  void feed(std::string_view bytes);
  StepStructure finish();

  /// The relations followed, each a graph of entity ids.
  enum Graph { kProducts, kRepresentations, kMappedItems, kGraphs };
  using Edge = std::pair<std::uint64_t, std::uint64_t>;

 private:
  enum class Token { reference, keyword, open, close, comma, equals, end, other };
  enum class Lexer {
    normal,
    string,
    string_quote,
    binary,
    slash,
    comment,
    comment_star,
    hash,
    word
  };
  enum class Phase { start, named, equals, body, skip };
  enum class Record { none, usage, relationship, representation, mapped_item, map };

  void lex(char c);
  void finish_word();
  void token(Token kind);
  void body_token(Token kind);
  void reference(std::uint64_t id);
  void end_statement();

  Lexer lexer_ = Lexer::normal;
  std::string word_;          // a keyword being read (truncated: long names match nothing)
  std::uint64_t number_ = 0;  // an entity id being read
  bool number_valid_ = false;
  Phase phase_ = Phase::start;
  std::uint64_t instance_ = 0;
  std::int64_t depth_ = 0;  // parentheses open in the statement
  std::int64_t record_depth_ = 1;
  Record pending_ = Record::none, record_ = Record::none;
  std::int64_t argument_ = 0;
  std::uint64_t from_ = 0, to_ = 0;
  std::vector<Edge> edges_[kGraphs];
  StepStructure structure_;
};

/// Scans the file at `path` (read in blocks).
/// @throw IoError if it cannot be read.
StepStructure scan_step_structure(const std::filesystem::path& path);

/// Refuses what OCCT's reader cannot survive, before it opens the file: a cycle in the
/// assembly or representation relations, or nesting deeper than kMaxAssemblyDepth; and more
/// product usages than `max_occurrences` (0: no limit), which it reads in quadratic time.
/// @throw InputError naming the file, what was found and, for the occurrences, how to raise it.
void check_step_structure(const std::filesystem::path& path, const StepStructure& structure,
                          std::uint64_t max_occurrences);

}  // namespace tetrapage::detail
