// The replay's worker processes (worker_pool.hpp): fork, pipes, frames,
// crash and timeout detection. Nothing here knows what a task is.
#include "jobs/replay/worker_pool.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <new>
#include <stdexcept>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "acquisition/contained_read.hpp"
#include "jobs/replay/record_wire.hpp"

namespace piezo::jobs::replay {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void write_all(int fd, const void* data, std::size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) throw std::runtime_error(std::string("pipe write: ") + std::strerror(errno));
    p += w;
    n -= static_cast<std::size_t>(w);
  }
}

bool read_exact(int fd, void* data, std::size_t n) {
  char* p = static_cast<char*>(data);
  while (n) {
    const ssize_t r = ::read(fd, p, n);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    p += r;
    n -= static_cast<std::size_t>(r);
  }
  return true;
}

// Closes every descriptor above stdio except a and b (in a forked worker).
void keep_only_fds(int a, int b) {
  const int lo = std::min(a, b), hi = std::max(a, b);
  if (lo > 3) ::close_range(3, static_cast<unsigned>(lo - 1), 0);
  if (hi - lo > 1) ::close_range(static_cast<unsigned>(lo + 1), static_cast<unsigned>(hi - 1), 0);
  ::close_range(static_cast<unsigned>(hi + 1), ~0U, 0);
}

}  // namespace

WorkerPool::WorkerPool(WorkerPoolOptions opt, WorkerPoolCallbacks cb, const std::atomic<bool>& cancel)
    : opt_(opt), cb_(std::move(cb)), cancel_(cancel) {
  static_assert(std::atomic<int>::is_always_lock_free, "a count shared between processes must be lock-free");
  void* m = ::mmap(nullptr, sizeof(std::atomic<int>), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  if (m != MAP_FAILED) spare_ = new (m) std::atomic<int>(0);
}

WorkerPool::~WorkerPool() {
  for (auto& w : workers_) stop(w, /*kill_it=*/true);
  if (spare_) ::munmap(spare_, sizeof(std::atomic<int>));
}

void WorkerPool::run() {
  const std::size_t n = std::min(opt_.jobs, std::max<std::size_t>(1, opt_.tasks));
  // The cores asked for that no worker will have (fewer tasks than jobs): lent
  // from the start, so that one capture replayed with --jobs 2 is as fast as
  // with --jobs 1 (which runs the two-thread steps on two threads).
  const int unused = static_cast<int>(std::min<std::size_t>(opt_.jobs - n, 1024));
  if (spare_) spare_->store(unused, std::memory_order_relaxed);
  workers_.resize(n);
  for (auto& w : workers_) spawn(w);
  std::size_t next = 0;
  for (;;) {
    if (cancel_) {  // interrupted: what is under way is not reported (a rerun resumes it)
      for (auto& w : workers_) stop(w, true);
      return;
    }
    for (auto& w : workers_)
      if (!w.task && next < opt_.tasks) {
        if (w.pid < 0) spawn(w);
        const std::uint64_t i = next++;
        w.task = i;
        w.started = Clock::now();
        w.stage.clear();
        w.detail.clear();
        write_all(w.task_fd, &i, sizeof i);
      }
    bool busy = false;
    int idle = 0;
    for (const auto& w : workers_) {
      busy |= w.task.has_value();
      idle += !w.task;
    }
    if (!busy) break;
    if (spare_) spare_->store(unused + (next < opt_.tasks ? 0 : idle), std::memory_order_relaxed);
    wait_and_collect();
  }
  if (spare_) spare_->store(0, std::memory_order_relaxed);
  for (auto& w : workers_) stop(w, false);
}

void WorkerPool::spawn(Proc& w) {
  int task[2], result[2];
  if (::pipe2(task, O_CLOEXEC) != 0) throw std::runtime_error("replay: pipe: " + std::string(std::strerror(errno)));
  if (::pipe2(result, O_CLOEXEC) != 0) {
    ::close(task[0]), ::close(task[1]);
    throw std::runtime_error("replay: pipe: " + std::string(std::strerror(errno)));
  }
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    for (int fd : {task[0], task[1], result[0], result[1]}) ::close(fd);
    throw std::runtime_error("replay: cannot start a worker process: " + std::string(std::strerror(errno)));
  }
  if (pid == 0) {
    // The worker dies with the batch (a killed batch must not leave workers
    // behind that hold its results file open and locked).
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(1);
    // Only its own two pipe ends and stdio stay open: not the results file and
    // its lock, not the JSON lines, not a sibling's pipe (whose write end kept
    // here would hide that sibling's death from the batch).
    keep_only_fds(task[0], result[1]);
    worker_main(task[0], result[1]);
  }
  ::close(task[0]);
  ::close(result[1]);
  w.pid = pid;
  w.task_fd = task[1];
  w.result_fd = result[0];
  w.buf.clear();
  w.task.reset();
}

void WorkerPool::worker_main(int task_fd, int result_fd) {
  int code = 0;
  try {
    std::uint64_t i;
    while (read_exact(task_fd, &i, sizeof i)) {
      if (i >= opt_.tasks) break;
      auto stage = [&](const std::string& what, const std::string& detail) {
        const std::string f = frame('S', what + '\0' + detail);
        write_all(result_fd, f.data(), f.size());
      };
      const std::string f = frame('O', cb_.work(static_cast<std::size_t>(i), stage));
      write_all(result_fd, f.data(), f.size());
    }
  } catch (...) {
    code = 1;
  }
  ::_exit(code);  // no atexit handlers: the batch's open files are not this process's to flush
}

void WorkerPool::stop(Proc& w, bool kill_it) {
  if (w.pid < 0) return;
  if (kill_it) ::kill(w.pid, SIGKILL);
  if (w.task_fd >= 0) ::close(w.task_fd);  // EOF on its task pipe: the worker exits
  if (w.result_fd >= 0) ::close(w.result_fd);
  int status;
  while (::waitpid(w.pid, &status, 0) < 0 && errno == EINTR) {
  }
  w.pid = -1;
  w.task_fd = w.result_fd = -1;
  w.task.reset();
}

void WorkerPool::wait_and_collect() {
  std::vector<pollfd> fds;
  std::vector<Proc*> who;
  double wait_s = 0.2;  // the cancel flag is looked at this often
  for (auto& w : workers_)
    if (w.task) {
      fds.push_back({w.result_fd, POLLIN, 0});
      who.push_back(&w);
      wait_s = std::min(wait_s, std::max(0.0, opt_.task_timeout_s - seconds_since(w.started)));
    }
  const int r = ::poll(fds.data(), fds.size(), static_cast<int>(wait_s * 1000.0) + 1);
  if (r < 0 && errno != EINTR) throw std::runtime_error(std::string("replay: poll: ") + std::strerror(errno));
  for (std::size_t k = 0; r > 0 && k < fds.size(); ++k) {
    if (!fds[k].revents) continue;
    Proc& w = *who[k];
    char b[65536];
    const ssize_t n = ::read(w.result_fd, b, sizeof b);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      died(w);
      continue;
    }
    w.buf.append(b, static_cast<std::size_t>(n));
    char kind;
    std::string payload;
    try {
      while (w.task && next_frame(w.buf, kind, payload)) {
        if (kind == 'S') {
          const auto z = payload.find('\0');
          w.stage = payload.substr(0, z);
          if (z != std::string::npos) w.detail = payload.substr(z + 1);
        } else if (kind == 'O') {
          cb_.done(*w.task, payload);
          w.task.reset();
        }
      }
    } catch (const std::runtime_error&) {  // garbled frames: the worker is not trusted further
      ::kill(w.pid, SIGKILL);
      died(w);
    }
  }
  for (auto& w : workers_)
    if (w.task && seconds_since(w.started) > opt_.task_timeout_s) {
      ::kill(w.pid, SIGKILL);
      LostTask lost{*w.task, "hung", "", w.stage, w.detail, seconds_since(w.started)};
      stop(w, true);
      cb_.lost(lost);
    }
}

// The worker's pipe closed: it exited or died, maybe in the middle of a task.
void WorkerPool::died(Proc& w) {
  int status = 0;
  ::close(w.task_fd);
  ::close(w.result_fd);
  while (::waitpid(w.pid, &status, 0) < 0 && errno == EINTR) {
  }
  w.pid = -1;
  w.task_fd = w.result_fd = -1;
  if (!w.task) return;
  const std::string how = WIFSIGNALED(status) ? acq::describe_signal(WTERMSIG(status))
                                              : "exit code " + std::to_string(WEXITSTATUS(status));
  cb_.lost({*w.task, "crashed", how, w.stage, w.detail, seconds_since(w.started)});
  w.task.reset();
}

}  // namespace piezo::jobs::replay
