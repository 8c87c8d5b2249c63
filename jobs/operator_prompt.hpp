#pragma once
// A question from a worker thread to the person at the bench ("connect the
// SHORT standard"), answered from the GUI's frame loop: the worker blocks in
// ask() until answer() (or cancel) — the frame loop never waits. The GUI draws
// it as a modal dialog (ui/gui/calibration_prompt.hpp); any other front end
// can poll question() and call answer().
#include <atomic>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <string>

namespace piezo::jobs {

class OperatorPrompt {
 public:
  // Worker thread: poses `text` and waits; true = done, false = declined, or
  // `cancel` became true, or close() was called.
  bool ask(const std::string& text, const std::atomic<bool>* cancel = nullptr);
  // Frame loop: the pending question, if any.
  std::optional<std::string> question() const;
  // Frame loop: answers the pending question (ignored when none is pending).
  void answer(bool done);
  // Declines the pending question and every later one (shutdown).
  void close();

 private:
  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::optional<std::string> question_;
  std::optional<bool> answer_;
  bool closed_ = false;
};

}  // namespace piezo::jobs
