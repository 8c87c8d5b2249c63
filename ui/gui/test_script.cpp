#include "ui/gui/test_script.hpp"

#include <cfloat>

namespace piezo::gui {

namespace {
// Frames a click waits for its button before the script gives up (a
// button that is never drawn, e.g. Cancel after the job already ended).
constexpr int kMaxWaitFrames = 600;
constexpr int kSettleFrames = 5;  // plots fit their views, tooltips appear

bool quiet(const AppState& s) { return !s.job.busy() && s.tasks.idle(); }
}  // namespace

TestScript::TestScript(std::vector<std::string> clicks, std::optional<ImVec2> hover)
    : clicks_(std::move(clicks)), hover_(hover) {}

void TestScript::inject(ImGuiIO& io, const AppState& s) {
  if (!active()) return;
  io.MouseDown[0] = false;
  const bool clicking =
      phase_ == Phase::Hovering || phase_ == Phase::Pressing || phase_ == Phase::Releasing;
  const auto it = clicking ? s.button_rects.find(clicks_[next_]) : s.button_rects.end();
  if (clicking && it == s.button_rects.end()) {
    phase_ = Phase::Waiting;  // the button went away mid-click: start the click again
    io.MousePos = ImVec2(-FLT_MAX, -FLT_MAX);
  } else if (clicking) {
    const ImVec4 r = it->second;
    io.MousePos = ImVec2(0.5f * (r.x + r.z), 0.5f * (r.y + r.w));
    io.MouseDown[0] = phase_ == Phase::Pressing;
  } else if (phase_ == Phase::Settling || phase_ == Phase::Done) {
    io.MousePos = hover_ ? *hover_ : ImVec2(-FLT_MAX, -FLT_MAX);
  } else {
    io.MousePos = ImVec2(-FLT_MAX, -FLT_MAX);
  }
}

bool TestScript::done(const AppState& s) {
  if (!active()) return false;
  ++frames_in_phase_;
  auto go = [&](Phase p) {
    phase_ = p;
    frames_in_phase_ = 0;
  };
  switch (phase_) {
    case Phase::Waiting:
      if (next_ < clicks_.size()) {
        // The next button must be on screen and the background tasks idle (a
        // click on a button disabled while connecting would be lost). A job
        // still running is fine: that is how Cancel gets clicked.
        if (s.button_rects.count(clicks_[next_]) && s.tasks.idle()) {
          go(Phase::Hovering);
        } else if (frames_in_phase_ > kMaxWaitFrames && quiet(s)) {
          failure_ = "button '" + clicks_[next_] + "' never appeared";
          go(Phase::Settling);
        }
      } else if (quiet(s)) {
        go(Phase::Settling);
      }
      break;
    case Phase::Hovering:
      go(Phase::Pressing);
      break;
    case Phase::Pressing:
      go(Phase::Releasing);
      break;
    case Phase::Releasing:
      clicked_.push_back(clicks_[next_++]);
      go(Phase::Waiting);
      break;
    case Phase::Settling:
      if (frames_in_phase_ > kSettleFrames) go(Phase::Done);
      break;
    case Phase::Done:
      break;
  }
  return phase_ == Phase::Done;
}

}  // namespace piezo::gui
