#pragma once
// Scripted input for the tests under Xvfb (tests/gui): clicks named buttons
// in order, through ImGui's IO exactly as the GLFW backend feeds real input,
// waits for the work they start, parks the mouse, and says when to take the
// screenshot and exit. Inert when no click is given.
#include <imgui.h>

#include <optional>
#include <string>
#include <vector>

#include "ui/gui/app_state.hpp"

namespace piezo::gui {

class TestScript {
 public:
  // `hover`: where the mouse rests once the clicks are done (for a hover
  // read-out in the screenshot); none: outside the window.
  TestScript(std::vector<std::string> clicks, std::optional<ImVec2> hover);

  bool active() const { return !clicks_.empty(); }
  // Between the backend's NewFrame and ImGui::NewFrame: overrides the mouse.
  void inject(ImGuiIO& io, const AppState& s);
  // After the frame was rendered: advances; true once everything clicked has
  // finished and the window has settled (the moment for the screenshot).
  bool done(const AppState& s);
  // Labels clicked so far, and a failure (a button that never appeared).
  const std::vector<std::string>& clicked() const { return clicked_; }
  const std::string& failure() const { return failure_; }

 private:
  enum class Phase { Waiting, Hovering, Pressing, Releasing, Settling, Done };
  std::vector<std::string> clicks_, clicked_;
  std::optional<ImVec2> hover_;
  std::size_t next_ = 0;
  Phase phase_ = Phase::Waiting;
  int frames_in_phase_ = 0;
  std::string failure_;
};

}  // namespace piezo::gui
