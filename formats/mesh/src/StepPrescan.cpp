// The STEP pre-scan: a byte-at-a-time lexer of ISO 10303-21 (strings, comments, entity ids,
// keywords, parentheses), a statement parser that keeps, of each entity instance, only the
// arguments of the relations OCCT's reader follows recursively, and a depth-first search of
// each relation graph for cycles and the longest chain. Linear in the file, no recursion.

#include "StepPrescan.h"

#include <algorithm>
#include <array>
#include <fstream>
#include <limits>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage::detail {
namespace {

constexpr std::size_t kLongestKeyword = 64;

bool is_word_start(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_' || c == '!';
}
bool is_word_part(char c) {
  return is_word_start(c) || (c >= '0' && c <= '9') || c == '-';
}

bool ends_with(std::string_view text, std::string_view tail) {
  return text.size() >= tail.size() && text.substr(text.size() - tail.size()) == tail;
}

// The longest chain (in edges) and the first cycle of one relation graph.
struct GraphFacts {
  std::size_t longest = 0;
  std::vector<std::uint64_t> cycle;  // ids, the first repeated at the end
};

// Depth-first search without recursion over the edges (sorted in place): a node is grey while
// on the stack, black when done, its height known.
GraphFacts analyse(std::vector<StepScanner::Edge>& edges) {
  GraphFacts facts;
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  std::vector<std::uint64_t> nodes;
  nodes.reserve(2 * edges.size());
  for (const auto& [from, to] : edges) {
    nodes.push_back(from);
    nodes.push_back(to);
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  const auto index_of = [&](std::uint64_t id) {
    return std::size_t(std::lower_bound(nodes.begin(), nodes.end(), id) - nodes.begin());
  };
  // Edges are sorted by source: node i's are [first[i], first[i + 1]).
  std::vector<std::size_t> first(nodes.size() + 1, 0);
  for (const auto& edge : edges) ++first[index_of(edge.first) + 1];
  for (std::size_t i = 0; i < nodes.size(); ++i) first[i + 1] += first[i];
  enum : std::uint8_t { white, grey, black };
  std::vector<std::uint8_t> colour(nodes.size(), white);
  std::vector<std::size_t> height(nodes.size(), 0);
  std::vector<std::pair<std::size_t, std::size_t>> stack;  // node, next edge
  for (std::size_t root = 0; root < nodes.size(); ++root) {
    if (colour[root] != white) continue;
    colour[root] = grey;
    stack.push_back({root, first[root]});
    while (!stack.empty()) {
      auto& [node, next] = stack.back();
      if (next == first[node + 1]) {
        colour[node] = black;
        const std::size_t done = node;
        stack.pop_back();
        if (!stack.empty()) {
          std::size_t& parent_height = height[stack.back().first];
          parent_height = std::max(parent_height, height[done] + 1);
        }
        continue;
      }
      const std::size_t child = index_of(edges[next++].second);
      if (colour[child] == grey) {
        auto on_stack = std::find_if(stack.begin(), stack.end(),
                                     [&](const auto& entry) { return entry.first == child; });
        for (; on_stack != stack.end(); ++on_stack) facts.cycle.push_back(nodes[on_stack->first]);
        facts.cycle.push_back(nodes[child]);
        return facts;
      }
      if (colour[child] == black) {
        height[node] = std::max(height[node], height[child] + 1);
        continue;
      }
      colour[child] = grey;
      stack.push_back({child, first[child]});
    }
    facts.longest = std::max(facts.longest, height[root]);
  }
  return facts;
}

std::string describe_cycle(const char* what, const std::vector<std::uint64_t>& cycle) {
  std::string text = what;
  constexpr std::size_t kShown = 8;  // a long cycle is named by its first entities
  for (std::size_t i = 0; i < cycle.size(); ++i) {
    if (i == kShown && cycle.size() > kShown + 1) {
      text += " -> ... (" + std::to_string(cycle.size() - 1) + " in the cycle)";
      break;
    }
    text += (i == 0 ? " #" : " -> #") + std::to_string(cycle[i]);
  }
  return text;
}

int clamp_depth(std::size_t edges) {
  return int(std::min<std::size_t>(edges, std::numeric_limits<int>::max()));
}

}  // namespace

void StepScanner::feed(std::string_view bytes) {
  for (const char c : bytes) lex(c);
}

void StepScanner::lex(char c) {
  switch (lexer_) {
    case Lexer::string:  // '' inside a string is a quote
      if (c == '\'') lexer_ = Lexer::string_quote;
      return;
    case Lexer::string_quote:
      if (c == '\'') {
        lexer_ = Lexer::string;
        return;
      }
      lexer_ = Lexer::normal;
      break;
    case Lexer::binary:
      if (c == '"') lexer_ = Lexer::normal;
      return;
    case Lexer::comment:
      if (c == '*') lexer_ = Lexer::comment_star;
      return;
    case Lexer::comment_star:
      lexer_ = c == '/' ? Lexer::normal : c == '*' ? Lexer::comment_star : Lexer::comment;
      return;
    case Lexer::slash:
      if (c == '*') {
        lexer_ = Lexer::comment;
        return;
      }
      lexer_ = Lexer::normal;
      token(Token::other);
      break;
    case Lexer::hash:
      if (c >= '0' && c <= '9') {
        const auto digit = std::uint64_t(c - '0');
        if (number_ > (std::numeric_limits<std::uint64_t>::max() - digit) / 10)
          number_valid_ = false;
        number_ = number_ * 10 + digit;
        return;
      }
      lexer_ = Lexer::normal;
      if (number_valid_)
        reference(number_);
      else
        token(Token::other);
      break;
    case Lexer::word:
      if (is_word_part(c)) {
        if (word_.size() <= kLongestKeyword) word_ += c;
        return;
      }
      lexer_ = Lexer::normal;
      finish_word();
      break;
    case Lexer::normal:
      break;
  }
  // Lexer::normal: c starts a token.
  switch (c) {
    case '\'':
      lexer_ = Lexer::string;
      token(Token::other);
      return;
    case '"':
      lexer_ = Lexer::binary;
      token(Token::other);
      return;
    case '/':
      lexer_ = Lexer::slash;
      return;
    case '#':
      lexer_ = Lexer::hash;
      number_ = 0;
      number_valid_ = true;
      return;
    case '(':
      token(Token::open);
      return;
    case ')':
      token(Token::close);
      return;
    case ',':
      token(Token::comma);
      return;
    case '=':
      token(Token::equals);
      return;
    case ';':
      token(Token::end);
      return;
    case ' ':
    case '\t':
    case '\r':
    case '\n':
      return;
    default:
      break;
  }
  if (is_word_start(c)) {
    lexer_ = Lexer::word;
    word_.assign(1, c);
    return;
  }
  token(Token::other);  // numbers, enumerations, $, *, anything else
}

void StepScanner::finish_word() {
  pending_ = Record::none;
  if (word_ == "NEXT_ASSEMBLY_USAGE_OCCURRENCE" || word_ == "ASSEMBLY_COMPONENT_USAGE" ||
      word_ == "PRODUCT_DEFINITION_USAGE" || word_ == "PROMISSORY_USAGE_OCCURRENCE" ||
      word_ == "QUANTIFIED_ASSEMBLY_COMPONENT_USAGE")
    pending_ = Record::usage;
  else if (word_ == "REPRESENTATION_RELATIONSHIP" || word_ == "SHAPE_REPRESENTATION_RELATIONSHIP" ||
           word_ == "REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION")
    pending_ = Record::relationship;
  else if (word_ == "MAPPED_ITEM")
    pending_ = Record::mapped_item;
  else if (word_ == "REPRESENTATION_MAP")
    pending_ = Record::map;
  else if (ends_with(word_, "REPRESENTATION"))
    pending_ = Record::representation;
  token(Token::keyword);
}

void StepScanner::reference(std::uint64_t id) {
  if (phase_ == Phase::start) {
    instance_ = id;
    phase_ = Phase::named;
    return;
  }
  if (phase_ != Phase::body) {
    token(Token::other);
    return;
  }
  // An argument of the record being read: scalars at the record's depth, lists one deeper.
  const bool scalar = depth_ == record_depth_;
  switch (record_) {
    case Record::usage:
      if (scalar && argument_ == 3) from_ = id;
      if (scalar && argument_ == 4) to_ = id;
      break;
    case Record::relationship:
      if (scalar && argument_ == 2) from_ = id;
      if (scalar && argument_ == 3) to_ = id;
      break;
    case Record::representation:
      if (argument_ == 1 && depth_ == record_depth_ + 1)
        edges_[kMappedItems].push_back({instance_, id});
      break;
    case Record::mapped_item:
    case Record::map:
      if (scalar && argument_ == 1) edges_[kMappedItems].push_back({instance_, id});
      break;
    case Record::none:
      break;
  }
}

void StepScanner::token(Token kind) {
  if (kind == Token::end) {
    end_statement();
    return;
  }
  switch (phase_) {
    case Phase::start:  // a statement that is no instance (HEADER, section names)
      phase_ = Phase::skip;
      return;
    case Phase::named:
      phase_ = kind == Token::equals ? Phase::equals : Phase::skip;
      return;
    case Phase::equals:
      if (kind != Token::keyword && kind != Token::open) {
        phase_ = Phase::skip;
        return;
      }
      ++structure_.instances;
      phase_ = Phase::body;
      record_depth_ = kind == Token::open ? 2 : 1;  // a complex instance: (A(...) B(...))
      depth_ = 0;
      if (kind == Token::open) ++depth_;
      return;
    case Phase::body:
      body_token(kind);
      return;
    case Phase::skip:
      return;
  }
}

void StepScanner::body_token(Token kind) {
  switch (kind) {
    case Token::open:
      ++depth_;
      if (depth_ == record_depth_) {
        record_ = pending_;
        argument_ = 0;
        if (record_ == Record::usage) ++structure_.assembly_occurrences;
      }
      return;
    case Token::close:
      if (depth_ == record_depth_) {
        if ((record_ == Record::usage || record_ == Record::relationship) && from_ != 0 && to_ != 0)
          edges_[record_ == Record::usage ? kProducts : kRepresentations].push_back({from_, to_});
        record_ = Record::none;
        from_ = to_ = 0;
      }
      if (--depth_ < 0) phase_ = Phase::skip;
      return;
    case Token::comma:
      if (depth_ == record_depth_) ++argument_;
      return;
    case Token::keyword:
      if (depth_ != record_depth_ - 1) pending_ = Record::none;
      return;
    default:
      return;
  }
}

void StepScanner::end_statement() {
  phase_ = Phase::start;
  record_ = pending_ = Record::none;
  depth_ = 0;
  from_ = to_ = 0;
}

StepStructure StepScanner::finish() {
  constexpr std::array<const char*, kGraphs> kNames = {"product definitions", "representations",
                                                       "mapped representations"};
  for (int graph = 0; graph < kGraphs; ++graph) {
    const GraphFacts facts = analyse(edges_[graph]);
    edges_[graph] = {};
    if (!facts.cycle.empty() && structure_.cycle.empty())
      structure_.cycle = describe_cycle(kNames[graph], facts.cycle);
    const int depth = clamp_depth(facts.longest);
    if (graph == kProducts) structure_.assembly_depth = depth;
    if (graph == kRepresentations) structure_.representation_depth = depth;
    // A level of mapping is three links: representation -> item -> map -> representation.
    if (graph == kMappedItems) structure_.mapped_item_depth = depth / 3;
  }
  return structure_;
}

StepStructure scan_step_structure(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot open the file");
  StepScanner scanner;
  std::string block(1 << 20, '\0');
  while (in) {
    in.read(block.data(), std::streamsize(block.size()));
    scanner.feed(std::string_view(block.data(), std::size_t(in.gcount())));
  }
  if (in.bad()) throw IoError(path.string() + ": cannot read the file");
  return scanner.finish();
}

void check_step_structure(const std::filesystem::path& path, const StepStructure& structure,
                          std::uint64_t max_occurrences) {
  const std::string file = path.string();
  if (!structure.cycle.empty())
    throw InputError(file + ": the assembly is cyclic (" + structure.cycle +
                     "): a part cannot contain itself");
  const int depth = std::max(
      {structure.assembly_depth, structure.representation_depth, structure.mapped_item_depth});
  if (depth > kMaxAssemblyDepth)
    throw InputError(file + ": assemblies nested " + std::to_string(depth) +
                     " deep, more than the " + std::to_string(kMaxAssemblyDepth) + " levels read");
  if (max_occurrences != 0 && structure.assembly_occurrences > max_occurrences)
    throw InputError(
        file + ": " + std::to_string(structure.assembly_occurrences) +
        " part occurrences, more than the limit of " + std::to_string(max_occurrences) +
        " (OpenCASCADE reads them in quadratic time; --max-cad-occurrences raises it)");
}

}  // namespace tetrapage::detail
