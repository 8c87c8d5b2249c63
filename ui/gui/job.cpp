#include "ui/gui/app_state.hpp"

namespace piezo::gui {

Job::~Job() {
  cancel_ = true;
  if (thread_.joinable()) thread_.join();
}

bool Job::start(const ui::PipelineRequest& req) {
  if (running_) return false;
  if (thread_.joinable()) thread_.join();
  running_ = true;
  cancel_ = false;
  finished_ = false;
  progress_ = 0;
  thread_ = std::thread([this, req] {
    std::unique_ptr<ui::PipelineResult> res;
    std::string err;
    try {
      res = std::make_unique<ui::PipelineResult>(ui::run_pipeline(
          req,
          [this](const ui::PipelineProgress& p) {
            progress_ = static_cast<float>(p.fraction);
            std::lock_guard lock(mu_);
            stage_ = p.stage;
          },
          cancel_));
    } catch (const std::exception& e) {
      err = e.what();
    }
    {
      std::lock_guard lock(mu_);
      result_ = std::move(res);
      error_ = err;
    }
    finished_ = true;
    running_ = false;
  });
  return true;
}

std::string Job::stage() const {
  std::lock_guard lock(mu_);
  return stage_;
}

bool Job::take(std::unique_ptr<ui::PipelineResult>& result, std::string& error) {
  if (!finished_.exchange(false)) return false;
  std::lock_guard lock(mu_);
  result = std::move(result_);
  error = error_;
  return true;
}

}  // namespace piezo::gui
