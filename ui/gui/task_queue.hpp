#pragma once
// Short background work that must not run in the frame loop — the instrument
// probe, exports, PNG encoding — on one worker thread, first in first out.
// A task computes on the worker and returns an `Apply`: a small function that
// the frame loop runs on the UI thread (drain()) to put the outcome into the
// AppState. So the windows never share data with a running task.
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace piezo::gui {

struct AppState;

class TaskQueue {
 public:
  using Apply = std::function<void(AppState&)>;
  using Task = std::function<Apply()>;

  TaskQueue();
  ~TaskQueue();  // finishes the running task, drops the queued ones
  TaskQueue(const TaskQueue&) = delete;
  TaskQueue& operator=(const TaskQueue&) = delete;

  // `what` names the task in the log if it throws (a task should catch its
  // own errors and report them through its Apply; this is the safety net).
  void post(std::string what, Task task);
  // Runs the outcomes of finished tasks on the calling (UI) thread.
  void drain(AppState& s);
  // No task queued, running or waiting to be drained.
  bool idle() const;

 private:
  void loop();

  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::pair<std::string, Task>> queue_;
  std::vector<Apply> done_;
  bool busy_ = false, stop_ = false;
  std::thread thread_;  // last: starts after the members it uses
};

}  // namespace piezo::gui
