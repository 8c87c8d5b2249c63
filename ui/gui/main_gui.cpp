// piezobench-gui — the bench technician's program (Dear ImGui + GLFW + OpenGL 3).
// The frame loop only draws: work runs on the Job and TaskQueue threads
// (app_state.hpp) and comes back through collect_job() and drain().
//
// Test hooks (used by tests/gui under Xvfb, test_script.hpp): --click LABEL
// (repeatable) clicks those buttons in order once drawn; --wait-job exits when
// the work they started has finished; --hover X,Y rests the mouse there
// afterwards; --screenshot FILE saves the window then; --frame-stats FILE
// writes the frame times and what the windows showed; --timeout S bounds the run.
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

#include "jobs/demo_job.hpp"
#include "ui/allocator_policy.hpp"
#include "ui/gui/screenshot.hpp"
#include "ui/gui/test_script.hpp"
#include "ui/gui/windows.hpp"

using namespace piezo::gui;

namespace {
// The panels' background. They tile the window, so it is drawn once, by
// glClear, instead of as five translucent window rectangles: a software
// rasteriser (Mesa llvmpipe under Xvfb, where the GUI test runs) pays for
// every blended pixel, and the panel backgrounds were a third of the frame
// (12.9 → 8.7 ms at 1280 × 800 with nothing plotted). Dark style's WindowBg
// (0.06, 0.94 alpha) composited over the former clear colour (0.08, 0.08, 0.10).
constexpr float kBackground[3] = {0.061f, 0.061f, 0.062f};

void glfw_error(int code, const char* msg) {
  std::fprintf(stderr, "piezobench-gui: GLFW error %d: %s\n", code, msg);
}

// Windows in a fixed layout: plan and instruments on the left, plots on the
// right, results and diagnosis side by side below the plots.
void render_windows(AppState& s, int w, int h) {
  const float left = 380.0f, W = static_cast<float>(w), H = static_cast<float>(h);
  const float plan_h = H * 0.64f, plots_h = H * 0.58f, results_w = 0.45f * (W - left);
  // Pinned (ImGuiCond_Always): the panels tile the window and follow its size,
  // and none may be dragged over another (their backgrounds are the cleared
  // framebuffer, see kBackground).
  auto place = [](float x, float y, float width, float height) {
    ImGui::SetNextWindowPos(ImVec2(x, y), ImGuiCond_Always);
    ImGui::SetNextWindowSize(ImVec2(width, height), ImGuiCond_Always);
  };
  place(0, 0, left, plan_h);
  render_plan_window(s);
  place(0, plan_h, left, H - plan_h);
  render_instrument_window(s);
  place(left, 0, W - left, plots_h);
  render_plots_window(s);
  place(left, plots_h, results_w, H - plots_h);
  render_results_window(s);
  place(left + results_w, plots_h, W - left - results_w, H - plots_h);
  render_diagnosis_window(s);
}

std::string json_or_empty(const std::optional<Problem>& p, std::string Problem::*field) {
  return p ? (*p).*field : std::string();
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5)];
}

// What the test checks: frame times, and what the windows showed.
nlohmann::json frame_stats(const AppState& s, const TestScript& script) {
  nlohmann::json jobs = nlohmann::json::array();
  for (const auto& v : s.frame_ms_jobs)
    jobs.push_back({{"frames", v.size()},
                    {"median_ms", percentile(v, 0.5)},
                    {"p95_ms", percentile(v, 0.95)},
                    {"max_ms", v.empty() ? 0.0 : *std::max_element(v.begin(), v.end())},
                    {"frame_ms", v}});
  nlohmann::json j = {{"jobs", jobs},
                      {"idle_frames", s.frame_ms_idle.size()},
                      {"idle_median_ms", percentile(s.frame_ms_idle, 0.5)},
                      {"clicked", script.clicked()},
                      {"script_failure", script.failure()},
                      {"error", json_or_empty(s.error, &Problem::message)},
                      {"error_kind", s.error ? kind_name(s.error->kind) : ""},
                      {"error_advice", json_or_empty(s.error, &Problem::advice)},
                      {"instrument_state", static_cast<int>(s.instrument.state)},
                      {"idn_awg", s.instrument.idn_awg},
                      {"idn_daq", s.instrument.idn_daq},
                      {"instrument_error", json_or_empty(s.instrument.problem, &Problem::message)},
                      {"capture", s.result ? s.result->capture_path : ""},
                      {"params", nlohmann::json::array()},
                      {"verdict_shown", s.diagnosis_shown.verdict},
                      {"effects_shown", s.diagnosis_shown.effects},
                      {"limits_status", s.verdict ? s.verdict->status : ""},
                      {"limits_reasons", s.verdict ? s.verdict->reasons : std::vector<std::string>()},
                      {"log", s.log}};
  auto rect = [](const PlotView& v) {
    return nlohmann::json{v.frame.x, v.frame.y, v.frame.z, v.frame.w};
  };
  j["plan"] = {{"shots", s.request.plan.shots},
               {"calibration", s.calibration.enabled},
               {"heldout", s.request.heldout_plan.has_value()},
               {"noise", s.request.sim.noise_rel}};
  j["plots"] = {{"mag", rect(s.mag_view)},
                {"phase", rect(s.phase_view)},
                {"residual", rect(s.residual_view)},
                {"sv", rect(s.sv_view)}};
  if (s.result) {
    for (const auto& p : s.result->params)
      j["params"].push_back({{"name", p.name}, {"original", p.original}, {"updated", p.updated},
                             {"sigma", p.sigma ? nlohmann::json(*p.sigma) : nlohmann::json(nullptr)},
                             {"status", p.status}});
    if (const auto& d = s.result->diagnosis) {
      j["diagnosis"] = {{"verdict", d->verdict},
                        {"effects", d->effects.size()},
                        {"added", d->added},
                        {"regions", nlohmann::json::array()}};
      for (const auto& g : d->regions)
        if (g.points > 0)
          j["diagnosis"]["regions"].push_back({{"name", g.name},
                                               {"kind", g.kind},
                                               {"share", g.share},
                                               {"f_lo_hz", g.f_lo_hz},
                                               {"f_hi_hz", g.f_hi_hz}});
    }
  }
  return j;
}
}  // namespace

int main(int argc, char** argv) {
  piezo::ui::set_allocator_policy();
  CLI::App cli{"piezobench-gui — Measure and update", "piezobench-gui"};
  std::vector<std::string> clicks;
  std::string screenshot, stats_file, replay, replay_heldout, instrument = "sim", daq, sim_effects;
  std::string sim_disturbances;
  std::vector<float> hover;
  bool wait_job = false;
  double timeout_s = 0;
  // The CLI's defaults (issue 41 item 5): `piezobench demo`'s bench, shots,
  // fixture standards and held-out chirp (jobs::DemoRequest).
  const piezo::jobs::DemoRequest demo;
  int width = 1280, height = 800, shots = demo.shots;
  bool no_calibrate = demo.no_calibrate || demo.calibrate.empty();
  cli.add_option("--instrument", instrument,
                 "AWG address: sim | tcp://HOST:PORT | usbtmc://VID:PID[/SERIAL]");
  cli.add_option("--daq", daq, "DAQ address (default: tcp PORT+1; required for usbtmc)");
  cli.add_option("--sim-effects", sim_effects,
                 "Effects of the simulated bench, NAME=VALUE[,NAME=VALUE...]");
  cli.add_option(
      "--sim-disturbances", sim_disturbances,
      "Slow disturbances of the simulated bench, offset=V,hum=V[,mains=50|60],pink=PCT,...");
  cli.add_option("--shots", shots, "Shots in the plan")->capture_default_str()->check(CLI::PositiveNumber);
  cli.add_flag("--no-calibrate", no_calibrate,
               "Start with the fixture standards off (as `demo --no-calibrate`; the Plan panel can turn them on)");
  cli.add_option("--replay", replay, "Put this recorded capture in the plan panel for replay");
  cli.add_option("--replay-heldout", replay_heldout,
                 "… and this one beside it as its held-out capture (another drive of the same transducer)");
  std::string limits;
  cli.add_option("--limits", limits, "Put this limits file in the plan panel (load it with 'Limits...')");
  cli.add_option("--click", clicks, "Test hook: click these buttons in order once drawn");
  cli.add_flag("--wait-job", wait_job, "Test hook: exit when the clicked work has finished");
  cli.add_option("--hover", hover, "Test hook: rest the mouse at X Y after the clicks")
      ->expected(2)
      ->delimiter(',');
  cli.add_option("--screenshot", screenshot, "Test hook: save a PNG of the window before exiting");
  cli.add_option("--frame-stats", stats_file,
                 "Test hook: write frame times and what was shown (JSON)");
  cli.add_option("--timeout", timeout_s, "Exit with an error after this many seconds");
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
  TestScript script(clicks,
                    hover.size() == 2 ? std::optional(ImVec2(hover[0], hover[1])) : std::nullopt);
  glfwSwapInterval(script.active() ? 0
                                   : 1);  // tests measure the frame's work, not the wait for vsync

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // a fixed layout; no imgui.ini next to the captures
  ImGui::StyleColorsDark();
  ImGui::GetStyle().Colors[ImGuiCol_WindowBg].w = 0.0f;  // glClear draws it: kBackground
  ImGui_ImplGlfw_InitForOpenGL(win, true);
  ImGui_ImplOpenGL3_Init("#version 330");

  int rc = 0;
  {
    AppState state;
    // The demo's plan and simulated bench (the seed's lab measurement; the
    // simulated tube differs from the nominal model, the seed's Table 4/5
    // target, so that updating has something to do), its held-out chirp; no
    // transducer id of its own. The standards follow the Plan panel's form.
    state.request = piezo::jobs::demo_bench_request(demo);
    state.instrument.sim = piezo::jobs::demo_sim_request(demo);  // the panel's fields complete it
    state.request.plan.setup.transducer_id.reset();
    state.request.plan.shots = shots;
    if (state.request.heldout_plan) state.request.heldout_plan->shots = shots;
    state.calibration.enabled = !no_calibrate;
    state.request.calibration.clear();  // attach_calibration fills it from the form at each measurement
    std::snprintf(state.instrument.awg, sizeof state.instrument.awg, "%s", instrument.c_str());
    std::snprintf(state.instrument.daq, sizeof state.instrument.daq, "%s", daq.c_str());
    std::snprintf(state.instrument.sim_effects, sizeof state.instrument.sim_effects, "%s",
                  sim_effects.c_str());
    std::snprintf(state.instrument.sim_disturbances, sizeof state.instrument.sim_disturbances, "%s",
                  sim_disturbances.c_str());
    std::snprintf(state.replay_path, sizeof state.replay_path, "%s", replay.c_str());
    std::snprintf(state.heldout_path, sizeof state.heldout_path, "%s", replay_heldout.c_str());
    std::snprintf(state.limits_path, sizeof state.limits_path, "%s", limits.c_str());
    connect_instruments(state);  // on the task thread: *IDN? shows as soon as the bench answers

    const auto t_start = std::chrono::steady_clock::now();
    while (!glfwWindowShouldClose(win)) {
      const auto t_frame = std::chrono::steady_clock::now();
      glfwPollEvents();
      ImGui_ImplOpenGL3_NewFrame();
      ImGui_ImplGlfw_NewFrame();
      // Scripted input goes through ImGui's IO after the backend wrote the real mouse state.
      script.inject(ImGui::GetIO(), state);
      ImGui::NewFrame();
      state.button_rects.clear();  // refilled by the buttons drawn this frame

      int w = 0, h = 0;
      glfwGetFramebufferSize(win, &w, &h);
      collect_job(state);
      state.tasks.drain(state);
      render_windows(state, w, h);
      render_calibration_prompt(state.calibration_prompt);  // "connect the standard" while the job waits

      ImGui::Render();
      glViewport(0, 0, w, h);
      glClearColor(kBackground[0], kBackground[1], kBackground[2], 1.0f);
      glClear(GL_COLOR_BUFFER_BIT);
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());

      if (!state.png_request.empty()) {
        // Read back here, after rendering and before the swap (the frame is
        // complete); compress and write on the task thread.
        auto img = std::make_shared<Image>(read_framebuffer(w, h));
        state.tasks.post("png", [img, path = state.png_request]() -> TaskQueue::Apply {
          try {
            write_png(*img, path);
            return [path](AppState& st) { st.log.push_back("exported " + path); };
          } catch (...) {
            Problem pr = problem_from_current_exception("png export");
            return [pr](AppState& st) { st.error = pr; };
          }
        });
        state.png_request.clear();
      }
      const bool running = state.job.running();
      const bool finished = script.done(state);
      if (finished && !screenshot.empty()) save_framebuffer_png(screenshot, w, h);
      glfwSwapBuffers(win);
      // The frame time is the work of one frame (input, drawing, swap); the
      // pacing wait below is not part of it.
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_frame)
              .count();
      (running && !state.frame_ms_jobs.empty() ? state.frame_ms_jobs.back() : state.frame_ms_idle)
          .push_back(ms);
      // Pacing: at most 60 frames/s while something runs, 10 when nothing
      // does; input ends the wait at once. Xvfb (and some drivers) have no
      // vsync, and an unpaced loop would take the CPU that the job needs.
      const bool active = state.job.busy() || !state.tasks.idle() || script.active();
      const double period_ms = active ? 1000.0 / 60 : 100.0;
      if (ms < period_ms) glfwWaitEventsTimeout((period_ms - ms) / 1000.0);

      if (finished && (wait_job || !screenshot.empty())) break;
      if (timeout_s > 0 &&
          std::chrono::steady_clock::now() - t_start > std::chrono::duration<double>(timeout_s)) {
        std::fprintf(stderr, "piezobench-gui: timeout after %.0f s\n", timeout_s);
        state.job.cancel();
        rc = 1;
        break;
      }
    }

    if (!stats_file.empty()) std::ofstream(stats_file) << frame_stats(state, script).dump(2);
    if (!script.failure().empty())
      std::fprintf(stderr, "piezobench-gui: %s\n", script.failure().c_str());
    if (rc == 0 && !script.failure().empty()) rc = 3;
    if (rc == 0 && state.error) rc = 2;
  }  // the job and task threads end here, before the GL context goes
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(win);
  glfwTerminate();
  return rc;
}
