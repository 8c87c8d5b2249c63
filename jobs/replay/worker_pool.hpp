#pragma once
// The replay's worker processes (jobs/replay/): a pool of forked copies of
// this process that each do the tasks the batch sends them (a task's index, 8
// bytes on its task pipe) and answer with frames (record_wire.hpp) on their
// result pipe: 'S' a stage reached, 'O' the task's outcome. The batch stays one
// thread; it alone sees the outcomes, in the order they arrive. A worker that
// dies (a crash inside a library, e.g. libhdf5 on a damaged file) or overruns
// the task timeout costs that task only: it is reported lost and a new worker
// takes the next task. What a task is and what its outcome means is the
// caller's (replay_batch.cpp): the pool knows indices and bytes.
#include <atomic>
#include <chrono>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <sys/types.h>

namespace piezo::jobs::replay {

struct WorkerPoolOptions {
  std::size_t tasks = 0;          // indices 0 .. tasks-1, handed out in order
  std::size_t jobs = 1;           // worker processes at most (never more than tasks, at least 1)
  double task_timeout_s = 600.0;  // a worker still on one task after this is killed
};

// A task that did not come back: its worker died, or it overran the timeout.
struct LostTask {
  std::size_t task = 0;
  std::string kind;          // "crashed" (the worker exited or died) or "hung" (killed at the timeout)
  std::string how;           // crashed: the signal, or "exit code N"; hung: ""
  std::string stage, detail;  // the last stage the worker reported for it ("" if none)
  double elapsed_s = 0.0;
};

struct WorkerPoolCallbacks {
  // In a worker: does task i and returns its outcome's bytes; `stage(what,
  // detail)` tells the batch where it is (the last one names a crash).
  std::function<std::string(std::size_t i,
                            const std::function<void(const std::string& what, const std::string& detail)>& stage)>
      work;
  // In the batch: an outcome arrived.
  std::function<void(std::size_t i, const std::string& outcome)> done;
  // In the batch: a task was lost (the worker is already reaped).
  std::function<void(const LostTask&)> lost;
};

class WorkerPool {
 public:
  WorkerPool(WorkerPoolOptions opt, WorkerPoolCallbacks cb, const std::atomic<bool>& cancel);
  ~WorkerPool();  // kills and reaps the workers still running
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Hands out every task and collects every outcome; returns when all came back
  // or were lost, or at once (workers killed, under-way tasks not reported)
  // when `cancel` is set. Throws std::runtime_error when no worker can be
  // started or a pipe fails; what `done` and `lost` throw passes through.
  void run();

  // How many workers idle with no task left to hand them (0 until the tasks
  // run out), plus the jobs no worker was started for (fewer tasks than
  // jobs), in memory the workers share with the batch: a worker's fit may
  // borrow a core while it is above zero (update/output_error/spare_core.hpp).
  // nullptr if that memory could not be had (then none is lent).
  const std::atomic<int>* spare_cores() const { return spare_; }

 private:
  using Clock = std::chrono::steady_clock;
  struct Proc {
    pid_t pid = -1;
    int task_fd = -1, result_fd = -1;
    std::string buf;
    std::optional<std::size_t> task;
    Clock::time_point started;
    std::string stage, detail;
  };
  void spawn(Proc& w);
  [[noreturn]] void worker_main(int task_fd, int result_fd);
  void stop(Proc& w, bool kill_it);
  void wait_and_collect();
  void died(Proc& w);

  WorkerPoolOptions opt_;
  WorkerPoolCallbacks cb_;
  std::atomic<int>* spare_ = nullptr;  // (mmap'd shared, anonymous)
  const std::atomic<bool>& cancel_;
  std::vector<Proc> workers_;
};

}  // namespace piezo::jobs::replay
