#include "acquisition/contained_read.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <mutex>
#include <string>

#include "acquisition/h5_handle.hpp"

namespace piezo::acq {

namespace {

constexpr int kRefused = 3;  // the child's read threw CaptureError: message on the pipe
constexpr int kOther = 4;    // another exception: message on the pipe

void write_all(int fd, const std::string& s) {
  std::size_t off = 0;
  while (off < s.size()) {
    const ssize_t w = ::write(fd, s.data() + off, s.size() - off);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return;
    off += static_cast<std::size_t>(w);
  }
}

// In the child: read, report, _exit. Never returns.
[[noreturn]] void child_read(const std::filesystem::path& file, const ReadOptions& ro, int fd) {
  int code = 0;
  try {
    (void)read_capture(file, ro);
  } catch (const CaptureError& e) {
    write_all(fd, e.h5path() + std::string(1, '\0') + e.problem());
    code = kRefused;
  } catch (const std::exception& e) {
    write_all(fd, e.what());
    code = kOther;
  } catch (...) {
    code = kOther;
  }
  ::_exit(code);
}

}  // namespace

std::string describe_signal(int sig) {
  const char* name = sig == SIGSEGV   ? "SIGSEGV"
                     : sig == SIGABRT ? "SIGABRT"
                     : sig == SIGBUS  ? "SIGBUS"
                     : sig == SIGFPE  ? "SIGFPE"
                     : sig == SIGILL  ? "SIGILL"
                     : sig == SIGKILL ? "SIGKILL"
                                      : nullptr;
  const char* what = ::strsignal(sig);
  std::string s = name ? name : "signal " + std::to_string(sig);
  if (what) s += std::string(" (") + what + ")";
  return s;
}

#if defined(__SANITIZE_ADDRESS__)
#define PIEZO_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PIEZO_UNDER_ASAN 1
#endif
#endif

void limit_memory_for_capture(std::uintmax_t file_bytes) {
#ifdef PIEZO_UNDER_ASAN
  (void)file_bytes;
#else
  std::uintmax_t pages = 0;  // the process's present virtual size (first field of statm)
  if (std::ifstream statm("/proc/self/statm"); !(statm >> pages)) return;
  const std::uintmax_t page = static_cast<std::uintmax_t>(::sysconf(_SC_PAGESIZE));
  const std::uintmax_t kBase = std::uintmax_t{2} << 30, kMax = std::uintmax_t{1} << 46;
  const std::uintmax_t per_file = file_bytes > kMax / 4400 ? kMax : 4400 * file_bytes;
  const std::uintmax_t cap = std::min(kMax, pages * page + kBase + per_file);
  rlimit r{};
  if (::getrlimit(RLIMIT_AS, &r) != 0) return;
  r.rlim_cur = r.rlim_max == RLIM_INFINITY ? cap : std::min<rlim_t>(cap, r.rlim_max);
  ::setrlimit(RLIMIT_AS, &r);
#endif
}

void probe_capture(const std::filesystem::path& path, const ContainedReadOptions& opt) {
  const std::string file = path.string();
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0)
    throw std::runtime_error("probe_capture: pipe: " + std::string(std::strerror(errno)));
  pid_t pid;
  {
    // No other thread is inside HDF5 while the child's copy of the library is made
    // (the recursive lock is held by this thread, which is the child's only thread).
    std::lock_guard lock(h5::h5_mutex());
    pid = ::fork();
    if (pid == 0) {
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // dies with its parent
      h5::renew_h5_mutex_in_forked_child();
      ::close(fds[0]);
      std::error_code ec;
      const auto size = std::filesystem::file_size(path, ec);
      limit_memory_for_capture(ec ? 0 : size);
      child_read(path, opt.read, fds[1]);
    }
  }
  ::close(fds[1]);
  if (pid < 0) {
    ::close(fds[0]);
    throw std::runtime_error("probe_capture: fork: " + std::string(std::strerror(errno)));
  }
  // Collect the child's message until EOF (it exited or died) or the deadline.
  std::string msg;
  bool timed_out = false;
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(opt.timeout_s);
  for (;;) {
    const double left =
        std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) {
      timed_out = true;
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    const int r = ::poll(&p, 1, static_cast<int>(std::min(left * 1000.0 + 1.0, 60000.0)));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) continue;  // re-check the deadline
    char buf[4096];
    const ssize_t n = ::read(fds[0], buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // EOF
    if (msg.size() < 65536) msg.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fds[0]);
  if (timed_out) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out) {
    char b[160];
    std::snprintf(b, sizeof b,
                  "reading did not finish within %.0f s (the HDF5 library hung on this file); "
                  "the file is unreadable and was left out",
                  opt.timeout_s);
    throw CaptureError(file, "/", b);
  }
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  // The child ends itself only with 0, kRefused or kOther: a signal, or any other
  // exit code (a sanitizer's handler turns a SIGSEGV into exit code 1), is a crash.
  if (WIFSIGNALED(status) || (code != 0 && code != kRefused && code != kOther))
    throw CaptureError(file, "/",
                       "the HDF5 library crashed reading this file (" +
                           (WIFSIGNALED(status) ? describe_signal(WTERMSIG(status))
                                                : "exit code " + std::to_string(code)) +
                           "): the file is damaged or not a capture; it is unreadable and was left "
                           "out");
  if (code == 0) return;
  if (code == kRefused) {
    const auto z = msg.find('\0');
    if (z != std::string::npos) throw CaptureError(file, msg.substr(0, z), msg.substr(z + 1));
  }
  throw CaptureError(file, "/",
                     "reading failed: " + (msg.empty() ? "exit code " + std::to_string(code) : msg));
}

Capture read_capture_contained(const std::filesystem::path& file,
                               const ContainedReadOptions& opt) {
  probe_capture(file, opt);
  return read_capture(file, opt.read);
}

}  // namespace piezo::acq
