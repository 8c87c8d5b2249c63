// The pipeline's worker thread (see Job in app_state.hpp).
#include <sys/resource.h>
#include <unistd.h>

#include "ui/gui/app_state.hpp"

namespace piezo::gui {

namespace {
// The worker runs below the UI's priority: on a two-core machine the
// pipeline's number crunching would otherwise compete on equal terms with the
// frame loop and the software rasteriser (llvmpipe under Xvfb), and frames
// would stretch while a job runs. Best effort: the job runs either way.
void lower_this_thread_priority() {
#ifdef __linux__
  setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), 10);
#endif
}
}  // namespace

Job::~Job() {
  cancel_ = true;
  if (thread_.joinable()) thread_.join();
}

bool Job::start(const jobs::PipelineRequest& req) {
  if (running_) return false;
  if (thread_.joinable()) thread_.join();
  running_ = true;
  cancel_ = false;
  finished_ = false;
  progress_ = 0;
  {
    std::lock_guard lock(mu_);
    stage_ = req.replay_capture.empty() ? "connect" : "open capture";
  }
  thread_ = std::thread([this, req] {
    lower_this_thread_priority();
    std::unique_ptr<jobs::PipelineResult> res;
    std::optional<Problem> problem;
    try {
      res = std::make_unique<jobs::PipelineResult>(jobs::run_pipeline(
          req,
          [this](const jobs::PipelineProgress& p) {
            progress_ = static_cast<float>(p.fraction);
            std::lock_guard lock(mu_);
            stage_ = p.stage;
          },
          cancel_));
    } catch (...) {
      problem = problem_from_current_exception(stage());
    }
    {
      std::lock_guard lock(mu_);
      result_ = std::move(res);
      problem_ = std::move(problem);
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

bool Job::take(std::unique_ptr<jobs::PipelineResult>& result, std::optional<Problem>& problem) {
  if (!finished_.exchange(false)) return false;
  std::lock_guard lock(mu_);
  result = std::move(result_);
  problem = std::move(problem_);
  return true;
}

}  // namespace piezo::gui
