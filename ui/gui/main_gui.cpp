// piezobench-gui — the bench technician's program (Dear ImGui + GLFW + OpenGL 3).
// The frame loop only draws: work runs on the Job thread (app_state.hpp).
//
// Test hooks (used by tests/gui under Xvfb): --click LABEL injects a mouse click
// on a tracked button once it is drawn; --wait-job waits for the job to end;
// --screenshot FILE saves the window after that; --frame-stats FILE writes the
// frame times measured while the job ran; --timeout S bounds the whole run.
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "ui/gui/screenshot.hpp"
#include "ui/gui/windows.hpp"

using namespace piezo::gui;

namespace {
void glfw_error(int code, const char* msg) { std::fprintf(stderr, "piezobench-gui: GLFW error %d: %s\n", code, msg); }

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"piezobench-gui — Measure and update", "piezobench-gui"};
  std::string click, screenshot, frame_stats, replay;
  bool wait_job = false;
  double timeout_s = 0;
  int width = 1280, height = 800;
  cli.add_option("--click", click, "Test hook: click the button with this label once drawn");
  cli.add_flag("--wait-job", wait_job, "Test hook: exit when the job has finished");
  cli.add_option("--screenshot", screenshot, "Test hook: save a PNG of the window before exiting");
  cli.add_option("--frame-stats", frame_stats, "Test hook: write frame times during the job (JSON)");
  cli.add_option("--timeout", timeout_s, "Exit with an error after this many seconds");
  cli.add_option("--replay", replay, "Open a recorded capture for replay");
  cli.add_option("--width", width);
  cli.add_option("--height", height);
  CLI11_PARSE(cli, argc, argv);

  glfwSetErrorCallback(glfw_error);
  if (!glfwInit()) {
    std::fprintf(stderr, "piezobench-gui: cannot initialise GLFW (no display? try xvfb-run)\n");
    return 1;
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  GLFWwindow* win = glfwCreateWindow(width, height, "piezobench", nullptr, nullptr);
  if (!win) {
    std::fprintf(stderr, "piezobench-gui: cannot open an OpenGL 3.3 window\n");
    glfwTerminate();
    return 1;
  }
  glfwMakeContextCurrent(win);
  glfwSwapInterval(click.empty() ? 1 : 0);  // tests measure real frame cost, not vsync

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // a fixed layout; no imgui.ini next to the captures
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(win, true);
  ImGui_ImplOpenGL3_Init("#version 330");

  AppState state;
  state.request.plan.setup.divider_r1_ohm = 3140.0;
  state.request.plan.samples = 20000;
  state.request.plan.pretrigger_samples = 200;
  state.request.plan.shots = 8;
  // The simulated bench's tube differs from the nominal model (the seed's
  // Table 4/5 target), so that updating has something to do.
  state.request.sim.isotropic = true;
  state.request.sim.set = "YE11=6.66e10,nu12=0.3333,d31=-210e-12,epsT33_rel=2294";
  state.request.sim.noise_rel = 0.005;
  if (!replay.empty()) std::snprintf(state.replay_path, sizeof state.replay_path, "%s", replay.c_str());

  enum class Script { Idle, Hovering, Pressing, Releasing, Waiting, Settling, Done } script =
      click.empty() ? Script::Idle : Script::Hovering;
  int settle_frames = 0, rc = 0;
  bool job_seen = false;
  const auto t_start = std::chrono::steady_clock::now();

  while (!glfwWindowShouldClose(win)) {
    const auto t_frame = std::chrono::steady_clock::now();
    glfwPollEvents();
    ImGuiIO& io = ImGui::GetIO();
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    // Scripted input goes through ImGui's IO like the GLFW backend's, after the
    // backend wrote the real mouse state: hover, press, release (a click).
    if (script != Script::Idle && script != Script::Waiting && script != Script::Settling &&
        script != Script::Done && state.button_rects.count(click)) {
      ImVec4 r = state.button_rects[click];
      io.MousePos = ImVec2(0.5f * (r.x + r.z), 0.5f * (r.y + r.w));
      io.MouseDown[0] = script == Script::Pressing;
      script = script == Script::Hovering ? Script::Pressing
               : script == Script::Pressing ? Script::Releasing
                                            : Script::Waiting;
    }
    ImGui::NewFrame();

    int w = 0, h = 0;
    glfwGetFramebufferSize(win, &w, &h);
    const float left = 380.0f;
    ImGui::SetNextWindowPos(ImVec2(0, 0), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(left, h * 0.7f), ImGuiCond_FirstUseEver);
    render_plan_window(state);
    ImGui::SetNextWindowPos(ImVec2(0, h * 0.7f), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(left, h * 0.3f), ImGuiCond_FirstUseEver);
    render_instrument_window(state);
    ImGui::SetNextWindowPos(ImVec2(left, 0), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(w - left, h * 0.66f), ImGuiCond_FirstUseEver);
    render_plots_window(state);
    ImGui::SetNextWindowPos(ImVec2(left, h * 0.66f), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(w - left, h * 0.34f), ImGuiCond_FirstUseEver);
    render_results_window(state);
    render_calibration_prompt(state.calibration_prompt);  // issue 10: "connect the standard" while the job waits

    if (state.job.take(state.result, state.error)) {
      state.mag_view.fitted = state.phase_view.fitted = state.sv_view.fitted = false;
      state.log.push_back(state.error.empty() ? "job finished" : "job failed: " + state.error);
      if (state.result)
        for (const auto& st : state.result->stages)
          state.log.push_back((st.ran ? "  ran " : "  skipped ") + st.name + ": " + st.note);
      if (state.result) {
        state.instrument.idn_awg = state.result->awg_idn;
        state.instrument.idn_daq = state.result->daq_idn;
        state.instrument.state = state.result->awg_idn.empty() ? "replay (no instrument)" : "connected";
      } else if (!state.error.empty()) {
        state.instrument.state = "error";
        state.instrument.last_error = state.error;
      }
    }

    ImGui::Render();
    glViewport(0, 0, w, h);
    glClearColor(0.08f, 0.08f, 0.1f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());

    if (!state.png_request.empty()) {  // after rendering, before the swap: the frame is complete
      try {
        save_framebuffer_png(state.png_request, w, h);
        state.log.push_back("exported " + state.png_request);
      } catch (const std::exception& e) {
        state.error = e.what();
      }
      state.png_request.clear();
    }
    const bool running = state.job.running();
    if (running) job_seen = true;
    if (script == Script::Waiting && job_seen && !running && !state.result && state.error.empty()) {
      // finished this frame: the result is taken on the next frame
    } else if (script == Script::Waiting && job_seen && !running) {
      script = Script::Settling;
    }
    if (script == Script::Settling && ++settle_frames > 5) {
      if (!screenshot.empty()) save_framebuffer_png(screenshot, w, h);
      script = Script::Done;
    }
    glfwSwapBuffers(win);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_frame).count();
    if (running) state.frame_ms_during_job.push_back(ms);

    if (script == Script::Done && (wait_job || !screenshot.empty())) break;
    if (timeout_s > 0 && std::chrono::steady_clock::now() - t_start > std::chrono::duration<double>(timeout_s)) {
      std::fprintf(stderr, "piezobench-gui: timeout after %.0f s\n", timeout_s);
      state.job.cancel();
      rc = 1;
      break;
    }
  }

  if (!frame_stats.empty()) {
    auto v = state.frame_ms_during_job;
    std::sort(v.begin(), v.end());
    nlohmann::json j = {{"frames_during_job", v.size()},
                        {"max_ms", v.empty() ? 0.0 : v.back()},
                        {"median_ms", v.empty() ? 0.0 : v[v.size() / 2]},
                        {"p95_ms", v.empty() ? 0.0 : v[static_cast<std::size_t>(0.95 * (v.size() - 1))]},
                        {"error", state.error},
                        {"capture", state.result ? state.result->capture_path : ""},
                        {"params", nlohmann::json::array()}};
    if (state.result)
      for (const auto& p : state.result->params)
        j["params"].push_back({{"name", p.name}, {"original", p.original}, {"updated", p.updated}});
    std::ofstream(frame_stats) << j.dump(2);
  }
  if (!state.error.empty()) rc = rc ? rc : 2;
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(win);
  glfwTerminate();
  return rc;
}
