#include "tetrapage/formats/base/Progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace tetrapage {

Progress::Progress(std::string label, std::uint64_t total, bool enabled,
                   ProgressCallback callback)
    : label_(std::move(label)),
      total_(total),
      callback_(std::move(callback)),
      enabled_(enabled),
      terminal_(enabled && ::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {
  last_notified_ = start_;
}

Progress::~Progress() {
  // A destructor must not throw: the callback is told of the end only by finish().
  callback_ = nullptr;
  if (enabled_ && !finished_ && done_ > 0) finish();
}

double Progress::elapsed_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::advance(std::uint64_t units) { set(done_ + units); }

void Progress::set(std::uint64_t done) {
  done_ = done;
  if (callback_) notify(false);
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  // A terminal gets at most 10 redraws a second; a log gets a line per 10% (or per 5 s).
  if (terminal_) {
    if (now - last_draw_ < std::chrono::milliseconds(100)) return;
  } else {
    const int percent = total_ ? static_cast<int>(100.0 * double(done_) / double(total_)) : -1;
    const bool step = total_ ? percent / 10 != last_percent_ / 10 : false;
    if (!step && now - last_draw_ < std::chrono::seconds(5)) return;
    last_percent_ = percent;
  }
  last_draw_ = now;
  draw(false);
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (total_ && done_ < total_) done_ = total_;
  if (callback_) notify(true);
  // A log already holds the line for this count; a terminal needs its closing newline.
  if (enabled_ && (terminal_ || done_ != last_drawn_done_)) draw(true);
}

void Progress::notify(bool final_call) {
  const auto now = std::chrono::steady_clock::now();
  if (!final_call && now - last_notified_ < std::chrono::milliseconds(100)) return;
  last_notified_ = now;
  callback_(label_, done_, total_);
}

void Progress::draw(bool final_line) {
  last_drawn_done_ = done_;
  const double seconds = elapsed_seconds();
  if (terminal_) {
    constexpr int width = 30;
    if (total_) {
      const double fraction = std::min(1.0, double(done_) / double(total_));
      const int filled = static_cast<int>(fraction * width);
      std::fprintf(stderr, "\r%-24s [%.*s%*s] %5.1f%% %.1fs", label_.c_str(), filled,
                   "==============================", width - filled, "", 100.0 * fraction,
                   seconds);
    } else {
      std::fprintf(stderr, "\r%-24s %llu %.1fs", label_.c_str(),
                   static_cast<unsigned long long>(done_), seconds);
    }
    if (final_line) std::fputc('\n', stderr);
  } else if (total_) {
    std::fprintf(stderr, "%s: %llu/%llu (%.0f%%) %.1fs\n", label_.c_str(),
                 static_cast<unsigned long long>(done_), static_cast<unsigned long long>(total_),
                 100.0 * double(done_) / double(total_), seconds);
  } else {
    std::fprintf(stderr, "%s: %llu %.1fs\n", label_.c_str(),
                 static_cast<unsigned long long>(done_), seconds);
  }
  std::fflush(stderr);
}

Progress& Progress::silent() {
  thread_local Progress quiet("", 0, false);
  return quiet;
}

}  // namespace tetrapage
