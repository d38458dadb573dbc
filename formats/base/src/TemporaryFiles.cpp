#include "tetrapage/formats/base/TemporaryFiles.h"

#include <signal.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <string>

namespace tetrapage {
namespace {

// Fixed storage, so that the signal handler reads it without allocating or locking.
constexpr std::size_t kSlots = 64, kPathBytes = 4096;
struct Slot {
  std::atomic<bool> used{false};
  char path[kPathBytes];
};
std::array<Slot, kSlots> slots;
std::mutex slots_mutex;  // between threads that register; the handler only reads

extern "C" void remove_and_reraise(int signal_number) {
  for (Slot& slot : slots)
    if (slot.used.load(std::memory_order_acquire)) ::unlink(slot.path);
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);
}

// The signals whose default action ends the process.
constexpr std::array kEndingSignals{SIGINT,  SIGTERM, SIGHUP,  SIGPIPE, SIGQUIT,   SIGALRM,
                                    SIGUSR1, SIGUSR2, SIGXCPU, SIGXFSZ, SIGVTALRM, SIGPROF};

bool process_exists(long pid) { return ::kill(pid_t(pid), 0) == 0 || errno == EPERM; }

}  // namespace

TemporaryFileGuard::TemporaryFileGuard(const std::filesystem::path& path) {
  const std::string text = std::filesystem::absolute(path).string();
  if (text.size() >= kPathBytes) return;
  const std::lock_guard lock(slots_mutex);
  for (std::size_t i = 0; i < kSlots; ++i) {
    if (slots[i].used.load(std::memory_order_relaxed)) continue;
    std::memcpy(slots[i].path, text.c_str(), text.size() + 1);
    slots[i].used.store(true, std::memory_order_release);
    slot_ = int(i);
    return;
  }
}

TemporaryFileGuard::~TemporaryFileGuard() {
  if (slot_ < 0) return;
  const std::lock_guard lock(slots_mutex);
  slots[std::size_t(slot_)].used.store(false, std::memory_order_release);
}

void remove_temporaries_on_signals() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction action {};
    action.sa_handler = remove_and_reraise;
    sigemptyset(&action.sa_mask);
    for (const int signal_number : kEndingSignals) {
      struct sigaction previous {};
      if (::sigaction(signal_number, nullptr, &previous) == 0 && previous.sa_handler == SIG_IGN)
        continue;
      ::sigaction(signal_number, &action, nullptr);
    }
  });
}

std::filesystem::path temporary_path(const std::filesystem::path& output) {
  return std::filesystem::path(output.string() + ".tmp-" + std::to_string(::getpid()));
}

std::vector<std::filesystem::path> remove_stale_temporaries(const std::filesystem::path& output) {
  std::vector<std::filesystem::path> removed;
  const std::string prefix = output.filename().string() + ".tmp-";
  std::filesystem::path folder = output.parent_path();
  if (folder.empty()) folder = ".";
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(folder, error)) {
    const std::string name = entry.path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string pid = name.substr(prefix.size());
    if (pid.find_first_not_of("0123456789") != std::string::npos || pid.size() > 9) continue;
    if (process_exists(std::stol(pid)) || !entry.is_regular_file(error)) continue;
    if (std::filesystem::remove(entry.path(), error)) removed.push_back(entry.path());
  }
  return removed;
}

}  // namespace tetrapage
