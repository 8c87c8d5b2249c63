#include "jobs/operator_prompt.hpp"

#include <chrono>

namespace piezo::jobs {

bool OperatorPrompt::ask(const std::string& text, const std::atomic<bool>* cancel) {
  std::unique_lock lock(mu_);
  if (closed_) return false;
  question_ = text;
  answer_.reset();
  // Wake up now and then to see a cancel flag set by someone who cannot notify us.
  while (!answer_ && !closed_ && !(cancel && cancel->load()))
    cv_.wait_for(lock, std::chrono::milliseconds(50));
  const bool ok = answer_.value_or(false) && !closed_ && !(cancel && cancel->load());
  question_.reset();
  answer_.reset();
  return ok;
}

std::optional<std::string> OperatorPrompt::question() const {
  std::lock_guard lock(mu_);
  return question_;
}

void OperatorPrompt::answer(bool done) {
  {
    std::lock_guard lock(mu_);
    if (!question_) return;
    answer_ = done;
  }
  cv_.notify_all();
}

void OperatorPrompt::close() {
  {
    std::lock_guard lock(mu_);
    closed_ = true;
  }
  cv_.notify_all();
}

}  // namespace piezo::jobs
