// The GUI's parts that need no window: how errors are classified and what the
// technician is told to do (error_advice), the residual plot built from a gap
// diagnosis (residual_plot), and the task queue that keeps exports and the
// instrument probe off the frame loop.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>

#include "acquisition/capture.hpp"
#include "dsp/mode_figures.hpp"
#include "tests/dsp/bvd_model.hpp"
#include "jobs/mode_nyquist.hpp"
#include "drivers/instrument_uri.hpp"
#include "drivers/scpi_client.hpp"
#include "drivers/transport.hpp"
#include "ui/gui/app_state.hpp"
#include "ui/gui/driver_choices.hpp"
#include "ui/gui/error_advice.hpp"
#include "ui/gui/palette.hpp"
#include "ui/gui/residual_plot.hpp"

using namespace piezo;
using namespace piezo::gui;

namespace {
template <class E>
Problem classify(const E& e, const std::string& stage) {
  try {
    throw e;
  } catch (...) {
    return problem_from_current_exception(stage);
  }
}
}  // namespace

TEST(ErrorAdvice, ClassifiesByExceptionType) {
  using drivers::TransportError;
  const auto conn = classify(
      TransportError(TransportError::Kind::Io, "tcp://10.0.0.5:5025: cannot connect"), "connect");
  EXPECT_EQ(conn.kind, ErrorKind::Connection);
  EXPECT_EQ(conn.message, "tcp://10.0.0.5:5025: cannot connect");
  EXPECT_EQ(conn.stage, "connect");
  EXPECT_NE(conn.advice.find("PORT+1"), std::string::npos) << conn.advice;

  const auto inst =
      classify(drivers::InstrumentError("-222,\"Data out of range\""), "acquire: shot 1/8");
  EXPECT_EQ(inst.kind, ErrorKind::Instrument);
  EXPECT_NE(inst.advice.find("limits"), std::string::npos) << inst.advice;

  const auto file =
      classify(acq::CaptureError("x.h5", "/", "not a readable HDF5 file"), "open capture");
  EXPECT_EQ(file.kind, ErrorKind::File);
  EXPECT_NE(file.advice.find("piezo-capture/1"), std::string::npos) << file.advice;

  // Bad input: the advice depends on where it was typed.
  const auto addr = classify(std::invalid_argument("unknown scheme"), "connect");
  const auto plan = classify(std::invalid_argument("shots must be > 0"), "acquire: shot 0/0");
  EXPECT_EQ(addr.kind, ErrorKind::Input);
  EXPECT_NE(addr.advice.find("usbtmc://"), std::string::npos) << addr.advice;
  EXPECT_NE(plan.advice.find("plan"), std::string::npos) << plan.advice;

  const auto other =
      classify(std::runtime_error("update: the estimate has no low-frequency capacitance"),
               "update: extended CMCM");
  EXPECT_EQ(other.kind, ErrorKind::Other);
  EXPECT_NE(other.advice.find("geometry"), std::string::npos) << other.advice;
}

TEST(ErrorAdvice, ResultProblemsNeedAction) {
  jobs::PipelineResult ok;
  ok.stages = {
      {"acquire", true, ""}, {"estimate", true, ""}, {"update", true, ""}, {"diagnose", true, ""}};
  EXPECT_TRUE(result_problems(ok).empty());

  jobs::PipelineResult r;
  r.stages = {{"update", false, "extended CMCM did NOT converge"},
              {"diagnose", false, "failed: needs at least 3 repeated shots"}};
  r.warnings = {"cancelled during acquisition; kept 2 shot(s)", "overlay estimators: too short"};
  const auto p = result_problems(r);
  ASSERT_EQ(p.size(), 3u);
  for (const auto& x : p) {
    EXPECT_EQ(x.kind, ErrorKind::Attention);
    EXPECT_FALSE(x.advice.empty());
  }
  EXPECT_EQ(p[0].stage, "update");
  EXPECT_EQ(p[1].stage, "diagnose");
  EXPECT_NE(p[1].advice.find("Shots"), std::string::npos) << p[1].advice;
  EXPECT_EQ(p[2].stage, "acquire");
  // "diagnose: not requested" is a choice, not a problem.
  jobs::PipelineResult skipped;
  skipped.stages = {{"diagnose", false, "not requested"}};
  EXPECT_TRUE(result_problems(skipped).empty());
}

TEST(ResidualPlot, RegionsShadedByKindAndCurvesInKhz) {
  update::GapDiagnosis d;
  d.before.f_hz = {1e3, 2e3, 50e3};
  d.before.residual_db = {0.1, -0.2, 1.5};
  d.before.residual_deg = {1, 2, 3};
  d.before.sigma_db = {0.05, 0.05, 0.5};
  d.before.sigma_deg = {0.5, 0.5, 0.5};
  d.after = d.before;
  update::GapRegion cap;
  cap.name = "capacitive band";
  cap.f_lo_hz = 1e3;
  cap.f_hi_hz = 40e3;
  cap.points = 10;
  cap.kind = "phase";
  cap.share = 0.6;
  update::GapRegion res = cap;
  res.name = "resonance 1";
  res.f_lo_hz = 40e3;
  res.f_hi_hz = 60e3;
  res.kind = "frequency shift";
  res.shift_pct = 0.12;
  update::GapRegion empty = cap;
  empty.points = 0;  // no measured frequency in it: not drawn
  d.regions = {cap, res, empty};

  auto spec = residual_plot_spec(d, false);
  ASSERT_EQ(spec.bands.size(), 2u);
  EXPECT_EQ(im_colour(spec.bands[0].colour), kColRegionPhase);
  EXPECT_EQ(im_colour(spec.bands[1].colour), kColRegionShift);
  EXPECT_DOUBLE_EQ(spec.bands[1].x0, 40.0);  // kHz
  EXPECT_NE(spec.bands[1].detail.find("+0.120 %"), std::string::npos) << spec.bands[1].detail;
  // ±2σ (one listed, one not) and the base residual; no added effect, no second residual.
  ASSERT_EQ(spec.series.size(), 3u);
  EXPECT_DOUBLE_EQ(spec.series[0].y[2], 1.0);
  EXPECT_DOUBLE_EQ(spec.series[1].y[2], -1.0);
  EXPECT_FALSE(spec.series[1].listed);
  EXPECT_EQ(im_colour(spec.series[2].colour), kColResidual);
  EXPECT_DOUBLE_EQ(spec.series[2].x[2], 50.0);
  EXPECT_DOUBLE_EQ(spec.series[2].y[1], -0.2);

  d.added = {"series_resistance"};
  spec = residual_plot_spec(d, true);
  ASSERT_EQ(spec.series.size(), 4u);
  EXPECT_EQ(im_colour(spec.series[3].colour), kColResidualAfter);
  EXPECT_NE(spec.series[3].label.find("series_resistance"), std::string::npos);
  EXPECT_DOUBLE_EQ(spec.series[2].y[2], 3.0);  // phase, degrees
  EXPECT_EQ(spec.y_label, "deg");
}

TEST(Palette, BlendOverMatchesGlBlending) {
  // 110/255 of orange over the plot background, per channel: bg + (fg − bg)·α.
  const Rgb c = blend_over(kColRegionShift, kColPlotBg);
  EXPECT_EQ(c.r, 20 + (255 - 20) * 110 / 255);
  EXPECT_EQ(c.g, 22 + (150 - 22) * 110 / 255);
  EXPECT_EQ(c.b, 28 + (0 - 28) * 110 / 255);
}

TEST(TaskQueue, RunsInOrderOffTheCallerAndAppliesOnDrain) {
  AppState s;  // owns a TaskQueue; no window needed
  const auto caller = std::this_thread::get_id();
  std::atomic<bool> off_caller{true};
  for (int i = 0; i < 5; ++i)
    s.tasks.post("task " + std::to_string(i), [i, caller, &off_caller]() -> TaskQueue::Apply {
      if (std::this_thread::get_id() == caller) off_caller = false;
      return [i](AppState& st) { st.log.push_back("applied " + std::to_string(i)); };
    });
  s.tasks.post("throws", []() -> TaskQueue::Apply { throw std::runtime_error("disk full"); });
  // Nothing reaches the state before drain().
  EXPECT_TRUE(s.log.empty());
  for (int k = 0; k < 500 && !s.tasks.idle(); ++k) {
    s.tasks.drain(s);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_TRUE(s.tasks.idle());
  EXPECT_TRUE(off_caller);
  ASSERT_EQ(s.log.size(), 6u);
  for (int i = 0; i < 5; ++i)
    EXPECT_EQ(s.log[static_cast<std::size_t>(i)], "applied " + std::to_string(i));
  EXPECT_EQ(s.log[5], "throws failed: disk full");
}

// The instrument window's driver combo (issue 20 item 4): one entry per
// registry family, each saying how it is chosen; "Use" fills addresses the
// bench opener accepts.
TEST(DriverChoices, OneEntryPerRegistryFamilyWithUsableAddresses) {
  const auto choices = piezo::gui::driver_choices();
  std::vector<std::string> keys;
  for (const auto& c : choices) {
    keys.push_back(c.key);
    EXPECT_FALSE(c.how.empty()) << c.key;
    EXPECT_FALSE(c.twin.empty()) << c.key;
    EXPECT_EQ(c.label.rfind(c.key + " [", 0), 0u) << c.label;
  }
  EXPECT_EQ(keys, (std::vector<std::string>{"keysight33500", "tektronix_awg", "infiniium",
                                            "redpitaya", "comedi"}));
  EXPECT_EQ(choices[1].awg_address, "sim?awg=tektronix");
  EXPECT_EQ(piezo::drivers::parse_instrument_uri(choices[1].awg_address).sim_awg, "tektronix");
  EXPECT_EQ(choices[4].daq_address, "comedi:///dev/comedi0?trigger=pfi0&aref=diff&channels=0,1");
  EXPECT_TRUE(choices[4].awg_address.empty());  // a DAQ: the AWG field stays
  EXPECT_NE(choices[4].how.find("comedi:///dev/comediN?"), std::string::npos) << choices[4].how;
  EXPECT_TRUE(choices[3].awg_address.empty() &&
              choices[3].daq_address.empty());  // no in-process twin
}

// The marker read-out (issue 19): the cursor snaps to the nearest snapping
// marker within the radius (never to one that does not ask for it), and the
// read-out gives the marker's label and each curve's own text at that x.
TEST(PlotReadout, SnapsToTheNearestResonanceAndReadsEachCurve) {
  using piezo::gui::Marker;
  std::vector<Marker> markers = {{50e3, {}, "fr 50 kHz", true}, {50.5e3, {}, "plain", false}, {52e3, {}, "fa 52 kHz", true}};
  auto to_px = [](double f) { return static_cast<float>(f / 100.0); };  // 100 Hz per pixel
  EXPECT_EQ(piezo::gui::snap_marker(markers, 503.0f, to_px), &markers[0]);   // 3 px from fr
  EXPECT_EQ(piezo::gui::snap_marker(markers, 505.0f, to_px), &markers[0]);   // "plain" is nearer but does not snap
  EXPECT_EQ(piezo::gui::snap_marker(markers, 515.0f, to_px), &markers[2]);   // 5 px from fa
  EXPECT_EQ(piezo::gui::snap_marker(markers, 510.0f, to_px), nullptr);       // 10 px from both
  piezo::gui::PlotSpec spec;
  std::vector<std::complex<double>> z = {{100, -100}, {1000, 0}, {0, 2000}};
  piezo::gui::Series s{"Z", {49e3, 50e3, 51e3}, {0, 0, 0}, {}, 1.0};
  s.readout = [z](std::size_t i) { return piezo::gui::impedance_readout(z[i]); };
  spec.series.push_back(s);
  const auto lines = piezo::gui::readout_at(spec, 50.2e3, &markers[0]);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].second, "fr 50 kHz");
  EXPECT_EQ(lines[1].second, "Z: |Z| 1 kohm  phase 0.0 deg  R 1 kohm  X 0 ohm");
  EXPECT_EQ(piezo::gui::impedance_readout({100, -100}), "|Z| 141.4 ohm  phase -45.0 deg  R 100 ohm  X -100 ohm");
  EXPECT_TRUE(piezo::gui::readout_at(spec, 60e3, nullptr).empty());  // outside the curve's range
}

// The admittance view of each mode (jobs/mode_nyquist.hpp) on an exact
// two-branch BVD network: the fitted network traced across the window is the
// network's own admittance (the fit is exact and the neighbour is included),
// and the estimate's points near fs lie on the motional circle (diameter 1/R1)
// — up to the change of ωC0 and of the neighbour across half a bandwidth.
TEST(ModeNyquist, ExactBvdPointsOnTheFittedCircle) {
  const auto m = bvd::make_bvd({50e3, 56e3}, {52e3, 57e3}, 2.5e-9, {1.0 / 400, 1.0 / 300});
  const Eigen::VectorXd f = piezo::dsp::make_grid(1e3, 120e3, 20);
  Eigen::VectorXcd z(f.size());
  for (Eigen::Index k = 0; k < f.size(); ++k) z[k] = m.impedance_at(f[k]);
  const auto figs = piezo::dsp::mode_figures(f, z, {}, {});
  ASSERT_EQ(figs.modes.size(), 2u);
  const std::vector<double> fv(f.data(), f.data() + f.size());
  const std::vector<std::complex<double>> zv(z.data(), z.data() + z.size());
  const auto ny = piezo::jobs::mode_nyquist(fv, zv, figs);
  ASSERT_EQ(ny.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& n = ny[i];
    const auto& b = m.branches[i];
    SCOPED_TRACE("mode " + std::to_string(i));
    EXPECT_NEAR(n.radius_s * 2.0 * b.R, 1.0, 1e-6);
    const double lo = figs.modes[i].window_lo_hz, hi = figs.modes[i].window_hi_hz;
    const std::complex<double> y_lo = 1.0 / m.impedance_at(lo), y_hi = 1.0 / m.impedance_at(hi);
    EXPECT_LT(std::abs(std::complex<double>(n.fit_g_s.front(), n.fit_b_s.front()) - y_lo), 1e-6 * std::abs(y_lo));
    EXPECT_LT(std::abs(std::complex<double>(n.fit_g_s.back(), n.fit_b_s.back()) - y_hi), 1e-6 * std::abs(y_hi));
    const double q = 1.0 / (2 * M_PI * n.fs_hz * b.R * b.C);
    int near = 0;
    for (std::size_t k = 0; k < n.f_hz.size(); ++k) {
      if (std::abs(n.f_hz[k] - n.fs_hz) > 0.5 * n.fs_hz / q) continue;
      ++near;
      const double d = std::hypot(n.g_s[k] - n.centre_g_s, n.b_s[k] - n.centre_b_s);
      EXPECT_NEAR(d / n.radius_s, 1.0, 0.02) << n.f_hz[k];
    }
    EXPECT_GE(near, 5);
  }
}

// The result of a job judged against the loaded limits (actions.cpp's
// judge_result, as collect_job and load_limits call it): no limits or no
// result, no verdict; otherwise pass or fail with the reasons.
TEST(Limits, JudgeResultAgainstTheLoadedLimits) {
  AppState s;
  judge_result(s);
  EXPECT_FALSE(s.verdict);
  auto r = std::make_shared<jobs::PipelineResult>();
  jobs::ParamRow p;
  p.name = "YE11";
  p.unit = "Pa";
  p.original = 6.3e10;
  p.updated = 6.5e10;
  r->params.push_back(p);
  s.result = r;
  judge_result(s);
  EXPECT_FALSE(s.verdict);  // no limits loaded
  s.limits = std::make_shared<const jobs::report::Limits>(jobs::report::parse_limits(
      "[[limit]]\nquantity = \"parameters.YE11\"\nmin = 6e10\nmax = 7e10\n", "l.toml"));
  judge_result(s);
  ASSERT_TRUE(s.verdict);
  EXPECT_EQ(s.verdict->status, "pass");
  r->params[0].updated = 7.5e10;
  judge_result(s);
  EXPECT_EQ(s.verdict->status, "fail");
  ASSERT_EQ(s.verdict->reasons.size(), 1u);
  EXPECT_EQ(s.verdict->reasons[0], "parameters.YE11 = 7.5e+10 > max 7e+10");
  s.limits = std::make_shared<const jobs::report::Limits>(jobs::report::parse_limits(
      "[[limit]]\nquantity = \"modes[0].k_eff\"\nmin = 0.1\n", "l.toml"));
  judge_result(s);  // the result has no per-mode figures: not measured, a fail
  EXPECT_EQ(s.verdict->status, "fail");
  EXPECT_EQ(s.verdict->reasons[0], "modes[0].k_eff not measured");
}
