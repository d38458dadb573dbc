// A CAD file read in a child process. Why fork() without exec(): the same code reads STEP for
// the command, the C API and the Python module, and only fork() works the same in all three
// (an exec'd helper would have to be found beside a library or an interpreter). fork() from a
// threaded process is safe here because of what the child touches: OpenCASCADE, which the
// caller never enters on this path (so no other thread holds its locks); glibc's malloc and
// stdio, whose locks fork() resets; and threads of its own (std::thread, never TBB). Every
// file descriptor but its pipe and stdio is closed in the child, and it dies with the caller.

#include "CadIsolation.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <limits>
#include <new>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage::detail {
namespace {

using Clock = std::chrono::steady_clock;

class FileDescriptor {
 public:
  explicit FileDescriptor(int fd = -1) : fd_(fd) {}
  ~FileDescriptor() { reset(); }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }
  void reset() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_;
};

// The child: killed and reaped unless waited for.
class ChildProcess {
 public:
  explicit ChildProcess(pid_t pid) : pid_(pid) {}
  ~ChildProcess() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGKILL);
    wait();
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  pid_t pid() const { return pid_; }
  // The wait status; -1 when the caller reaps children itself (SIGCHLD ignored).
  int wait() {
    int status = 0;
    pid_t got = 0;
    do got = ::waitpid(pid_, &status, 0);
    while (got < 0 && errno == EINTR);
    pid_ = 0;
    return got < 0 ? -1 : status;
  }
  // Without reaping it, so that wait() still reads its status.
  bool has_exited() const {
    siginfo_t info{};
    return ::waitid(P_PID, id_t(pid_), &info, WEXITED | WNOHANG | WNOWAIT) != 0 || info.si_pid != 0;
  }

 private:
  pid_t pid_;
};

// The stream's frames: the content, or the error the child caught.
enum Frame : std::uint8_t { kContent = 'C', kError = 'E', kOutOfMemory = 'M', kEnd = 'Z' };
enum ErrorClass : std::uint8_t { kIo, kFormat, kInput, kOther };

// Buffered writes to the pipe, in the child.
class PipeWriter {
 public:
  explicit PipeWriter(int fd) : fd_(fd) { buffer_.reserve(kBlock); }
  void bytes(const void* data, std::size_t size) {
    const auto* p = static_cast<const char*>(data);
    while (size > 0) {
      const std::size_t n = std::min(size, kBlock - buffer_.size());
      buffer_.insert(buffer_.end(), p, p + n);
      p += n;
      size -= n;
      if (buffer_.size() == kBlock) flush();
    }
  }
  template <class T>
  void value(const T& v) {
    bytes(&v, sizeof v);
  }
  void text(const std::string& s) {
    value(std::uint64_t(s.size()));
    bytes(s.data(), s.size());
  }
  void flush() {
    std::size_t done = 0;
    while (done < buffer_.size()) {
      const ssize_t n = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) ::_exit(3);  // the caller is gone
      done += std::size_t(n);
    }
    buffer_.clear();
  }

 private:
  static constexpr std::size_t kBlock = 1 << 16;
  int fd_;
  std::vector<char> buffer_;
};

struct StreamEnded {};  // the child closed the pipe early
struct TimedOut {};

// Reads the pipe in the caller, waiting at most until the deadline; notices a child that
// ended while another process still holds the pipe's write end.
class PipeReader {
 public:
  PipeReader(int fd, const ChildProcess& child, Clock::time_point deadline)
      : fd_(fd), child_(child), deadline_(deadline) {}
  void bytes(void* data, std::size_t size) {
    auto* p = static_cast<char*>(data);
    while (size > 0) {
      if (position_ == end_) fill();
      const std::size_t n = std::min(size, end_ - position_);
      std::memcpy(p, buffer_ + position_, n);
      position_ += n;
      p += n;
      size -= n;
    }
  }
  template <class T>
  T value() {
    T v;
    bytes(&v, sizeof v);
    return v;
  }
  std::string text() {
    const auto size = value<std::uint64_t>();
    if (size > kLongestText) throw StreamEnded{};
    std::string s(size, '\0');
    bytes(s.data(), size);
    return s;
  }
  // Appends `count` items, growing as they arrive (a wrong count cannot allocate ahead).
  template <class T>
  void items(std::vector<T>& out, std::uint64_t count) {
    while (count > 0) {
      const std::size_t n = std::size_t(std::min<std::uint64_t>(count, 1 << 16));
      const std::size_t old = out.size();
      out.resize(old + n);
      bytes(out.data() + old, n * sizeof(T));
      count -= n;
    }
  }

 private:
  static constexpr std::size_t kLongestText = 1 << 20;

  void fill() {
    for (;;) {
      if (deadline_ != Clock::time_point::max() && Clock::now() >= deadline_) throw TimedOut{};
      pollfd entry{fd_, POLLIN, 0};
      const int ready = ::poll(&entry, 1, 100);
      if (ready < 0 && errno != EINTR) throw StreamEnded{};
      if (ready > 0) {
        const ssize_t n = ::read(fd_, buffer_, sizeof buffer_);
        if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
        if (n <= 0) throw StreamEnded{};
        position_ = 0;
        end_ = std::size_t(n);
        return;
      }
      if (ready == 0 && child_.has_exited() && !data_waiting()) throw StreamEnded{};
    }
  }
  bool data_waiting() const {
    pollfd entry{fd_, POLLIN, 0};
    return ::poll(&entry, 1, 0) > 0 && (entry.revents & POLLIN) != 0;
  }

  int fd_;
  const ChildProcess& child_;
  Clock::time_point deadline_;
  char buffer_[1 << 16];
  std::size_t position_ = 0, end_ = 0;
};

void write_content(PipeWriter& out, const CadContent& content) {
  out.value(kContent);
  out.value(std::uint64_t(content.shapes.size()));
  for (const TessellatedShape& shape : content.shapes) {
    out.text(shape.name);
    out.text(shape.error);
    out.value(shape.deflection);
    out.value(shape.refused);
    out.value(std::uint64_t(shape.vertices.size()));
    out.bytes(shape.vertices.data(), shape.vertices.size() * sizeof(Vec3));
    out.value(std::uint64_t(shape.triangles.size()));
    out.bytes(shape.triangles.data(), shape.triangles.size() * sizeof(TriangleIndices));
  }
  out.value(std::uint64_t(content.instances.size()));
  for (const ShapeInstance& instance : content.instances) {
    out.value(std::uint64_t(instance.shape));
    out.value(instance.placement);
    out.text(instance.path);
  }
  out.value(kEnd);
}

// The content as sent; indices are checked, so that placing never reads out of bounds.
CadContent read_content(PipeReader& in) {
  CadContent content;
  const auto shapes = in.value<std::uint64_t>();
  for (std::uint64_t s = 0; s < shapes; ++s) {
    TessellatedShape shape;
    shape.name = in.text();
    shape.error = in.text();
    shape.deflection = in.value<double>();
    shape.refused = in.value<bool>();
    in.items(shape.vertices, in.value<std::uint64_t>());
    in.items(shape.triangles, in.value<std::uint64_t>());
    for (const TriangleIndices& t : shape.triangles)
      for (const std::uint32_t v : t)
        if (v >= shape.vertices.size()) throw StreamEnded{};
    content.shapes.push_back(std::move(shape));
  }
  const auto instances = in.value<std::uint64_t>();
  for (std::uint64_t i = 0; i < instances; ++i) {
    ShapeInstance instance;
    instance.shape = std::size_t(in.value<std::uint64_t>());
    instance.placement = in.value<Transform>();
    instance.path = in.text();
    if (instance.shape >= content.shapes.size()) throw StreamEnded{};
    content.instances.push_back(std::move(instance));
  }
  if (in.value<std::uint8_t>() != kEnd) throw StreamEnded{};
  return content;
}

[[noreturn]] void rethrow(ErrorClass kind, const std::string& message) {
  switch (kind) {
    case kIo:
      throw IoError(message);
    case kFormat:
      throw FormatError(message);
    case kInput:
      throw InputError(message);
    case kOther:
      break;
  }
  throw Error(message);
}

// This process's address space (VmSize), which the child inherits.
std::uint64_t address_space_bytes() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "VmSize:") {
      std::uint64_t kilobytes = 0;
      status >> kilobytes;
      return kilobytes * 1024;
    }
    status.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
  }
  return 0;
}

std::string megabytes(std::uint64_t bytes) {
  return std::to_string(bytes >> 20) + " MiB";
}

// In the child: its own signal dispositions, its one pipe, its limits.
void prepare_child(int write_fd, pid_t parent, std::uint64_t address_space) {
  for (const int signal_number :
       {SIGINT, SIGTERM, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGPIPE})
    ::signal(signal_number, SIG_DFL);
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != parent) ::_exit(4);  // the caller died before prctl
  // The child inherits the caller's unwritten stdout buffer, and OCCT writes to stdout: the
  // caller's pending lines came out twice (`mesh info a.step b.step | cat`). The child answers
  // through its pipe alone.
  if (const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC); null >= 0 && null != STDOUT_FILENO) {
    ::dup2(null, STDOUT_FILENO);
    ::close(null);
  }
  if (write_fd > 3) ::close_range(3, unsigned(write_fd) - 1, 0);
  ::close_range(unsigned(write_fd) + 1, ~0U, 0);
  if (address_space != 0 && memory_limit_applies()) {
    const rlimit limit{address_space, address_space};
    ::setrlimit(RLIMIT_AS, &limit);
  }
}

[[noreturn]] void run_child(int write_fd, const std::function<CadContent()>& read) {
  PipeWriter out(write_fd);
  try {
    const CadContent content = read();
    write_content(out, content);
  } catch (const std::bad_alloc&) {
    out.value(kOutOfMemory);
  } catch (const Error& error) {
    const ErrorClass kind = dynamic_cast<const IoError*>(&error)       ? kIo
                            : dynamic_cast<const FormatError*>(&error) ? kFormat
                            : dynamic_cast<const InputError*>(&error)  ? kInput
                                                                       : kOther;
    out.value(kError);
    out.value(kind);
    out.text(error.what());
  } catch (const std::exception& error) {
    out.value(kError);
    out.value(kOther);
    out.text(error.what());
  }
  out.flush();
  ::_exit(0);  // no atexit handlers or static destructors: they belong to the caller
}

// Why the child ended without an answer.
[[noreturn]] void explain_death(const std::string& file, const char* library, int status) {
  if (status != -1 && WIFSIGNALED(status))
    throw FormatError("reading '" + file + "' crashed " + library + " (signal " +
                      std::to_string(WTERMSIG(status)) +
                      (WTERMSIG(status) == SIGKILL ? ": out of memory?" : "") + ")");
  throw FormatError("reading '" + file + "' ended without an answer" +
                    (status != -1 && WIFEXITED(status)
                         ? " (exit " + std::to_string(WEXITSTATUS(status)) + ")"
                         : ""));
}

}  // namespace

bool memory_limit_applies() {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  return false;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer)
  return false;
#else
  return true;
#endif
#else
  return true;
#endif
}

std::uint64_t machine_memory() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  return pages > 0 && page > 0 ? std::uint64_t(pages) * std::uint64_t(page)
                               : (std::uint64_t(8) << 30);
}

CadContent read_in_child(const std::string& file, const IsolationLimits& limits,
                         const std::function<CadContent()>& read) {
  const std::uint64_t budget = limits.memory_bytes != 0 ? limits.memory_bytes : machine_memory();
  const std::uint64_t address_space = address_space_bytes() + budget;
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0)
    throw IoError("reading '" + file + "': cannot make a pipe: " + std::strerror(errno));
  FileDescriptor read_end(ends[0]), write_end(ends[1]);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0)
    throw IoError("reading '" + file + "': cannot start a process: " + std::strerror(errno));
  if (pid == 0) {
    ::close(ends[0]);
    prepare_child(ends[1], parent, address_space);
    run_child(ends[1], read);
  }
  ChildProcess child(pid);
  write_end.reset();
  const auto deadline = limits.seconds > 0
                            ? Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                 std::chrono::duration<double>(limits.seconds))
                            : Clock::time_point::max();
  PipeReader in(read_end.get(), child, deadline);
  try {
    switch (in.value<std::uint8_t>()) {
      case kContent: {
        CadContent content = read_content(in);
        child.wait();
        return content;
      }
      case kError: {
        const auto kind = in.value<ErrorClass>();
        const std::string message = in.text();
        child.wait();
        rethrow(kind, message);
      }
      case kOutOfMemory:
        throw InputError("reading '" + file + "' needs more memory than its limit of " +
                         megabytes(budget) + " (--cad-memory raises it)");
      default:
        throw StreamEnded{};
    }
  } catch (const TimedOut&) {
    throw InputError("reading '" + file + "' took longer than " +
                     std::to_string(int(limits.seconds)) + " s (--cad-timeout raises it)");
  } catch (const StreamEnded&) {
    explain_death(file, limits.library, child.wait());
  }
}

}  // namespace tetrapage::detail
