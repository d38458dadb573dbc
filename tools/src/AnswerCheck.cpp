#include "tetrapage/tools/AnswerCheck.h"

#include <cstdio>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/tools/AnswerFile.h"

namespace tetrapage {

AnswerCheck::AnswerCheck(const std::filesystem::path& answers, std::size_t poses, std::string who)
    : path_(answers), who_(std::move(who)) {
  if (path_.empty()) return;
  expected_ = read_answers(path_);
  if (expected_.size() != poses)
    throw InputError("answers '" + path_.string() + "' have " + std::to_string(expected_.size()) +
                     " rows but the path has " + std::to_string(poses) + " poses");
}

void AnswerCheck::record(std::size_t step, bool answer) {
  if (expected_.empty() || (expected_[step] != 0) == answer) return;
  if (++disagreements_ <= 10)
    std::fprintf(stderr, "step %zu: %s says %d, '%s' says %d\n", step, who_.c_str(), int(answer), path_.c_str(),
                 int(expected_[step]));
}

void AnswerCheck::finish() const {
  if (expected_.empty()) return;
  std::printf("disagreements with %s: %llu\n", path_.c_str(), static_cast<unsigned long long>(disagreements_));
  if (disagreements_ > 0)
    throw Error(std::to_string(disagreements_) + " answers disagree with '" + path_.string() + "'");
}

}  // namespace tetrapage
