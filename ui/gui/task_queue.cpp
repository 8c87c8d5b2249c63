#include "ui/gui/task_queue.hpp"

#include <exception>

#include "ui/gui/app_state.hpp"

namespace piezo::gui {

TaskQueue::TaskQueue() : thread_([this] { loop(); }) {}

TaskQueue::~TaskQueue() {
  {
    std::lock_guard lock(mu_);
    stop_ = true;
    queue_.clear();
  }
  cv_.notify_all();
  thread_.join();
}

void TaskQueue::post(std::string what, Task task) {
  {
    std::lock_guard lock(mu_);
    queue_.emplace_back(std::move(what), std::move(task));
  }
  cv_.notify_one();
}

void TaskQueue::drain(AppState& s) {
  std::vector<Apply> done;
  {
    std::lock_guard lock(mu_);
    done.swap(done_);
  }
  for (auto& apply : done) apply(s);
}

bool TaskQueue::idle() const {
  std::lock_guard lock(mu_);
  return queue_.empty() && !busy_ && done_.empty();
}

void TaskQueue::loop() {
  std::unique_lock lock(mu_);
  for (;;) {
    cv_.wait(lock, [this] { return stop_ || !queue_.empty(); });
    if (stop_) return;
    auto [what, task] = std::move(queue_.front());
    queue_.pop_front();
    busy_ = true;
    lock.unlock();
    Apply apply;
    try {
      apply = task();
    } catch (const std::exception& e) {
      apply = [what = what, msg = std::string(e.what())](AppState& s) {
        s.log.push_back(what + " failed: " + msg);
      };
    }
    lock.lock();
    if (apply) done_.push_back(std::move(apply));
    busy_ = false;
  }
}

}  // namespace piezo::gui
