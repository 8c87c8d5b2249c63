// The bench application under Xvfb (Mesa llvmpipe), driven by its test hooks
// (ui/gui/test_script.hpp): "Measure and update" on the simulated bench with a
// series resistance the model lacks — the capture, the parameter table, the
// gap verdict and effect ranking the diagnosis window showed, the JSON report
// exported through its button, and the screenshot (known plot colours inside
// the plot areas the GUI reports, the residual curves and the shade of the
// misfit's main region included); the frame times while the jobs ran are
// reported. Then the replay of a recorded capture, the errors (a file that is
// not a capture, no instrument at the address) shown with what to do, and
// Cancel.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <stb_image.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "acquisition/capture_file.hpp"
#include "jobs/demo_job.hpp"
#include "ui/gui/palette.hpp"

namespace fs = std::filesystem;
using piezo::gui::Rgb;

namespace {

// This test process's folder; each run gets a subfolder.
fs::path scratch() {
  return fs::temp_directory_path() / ("piezobench-gui-" + std::to_string(::getpid()));
}

// Removes the folder when the test passed; a failed test's files stay for a look.
struct ScratchCleanup {
  ~ScratchCleanup() {
    if (!::testing::Test::HasFailure()) fs::remove_all(scratch());
  }
};

struct GuiRun {
  int exit_code = -1;  // the GUI's own; 128 + N when signal N ended it (a crash)
  nlohmann::json stats;
  fs::path dir;
};

// Runs piezobench-gui under Xvfb in a fresh folder `name`, with `args` (test
// hooks included); the frame statistics come back parsed.
GuiRun run_gui(const std::string& name, const std::string& args) {
  GuiRun r;
  r.dir = scratch() / name;
  fs::remove_all(r.dir);
  fs::create_directories(r.dir);
  // The GUI's exit status is recorded by a wrapper script: xvfb-run's own is
  // not the program's. The X authority file lives in the run's folder (-f):
  // xvfb-run's own temporary folder, when something else on the machine
  // removed it first, made it exit with 5 before stopping its Xvfb.
  std::ofstream(r.dir / "run.sh") << "'" PIEZO_GUI "' " << args
                                  << " --frame-stats stats.json --timeout 240\necho $? > gui.rc\n";
  // Under `make test-asan`, LeakSanitizer reports blocks that Mesa's
  // dlopen'ed llvmpipe driver never frees (frames in "<unknown module>");
  // leak checks of our own code run in every other test, so they are off for
  // this process only (ASan's other checks stay on).
  const std::string cmd =
      "cd '" + r.dir.string() + "' && ASAN_OPTIONS=detect_leaks=0 xvfb-run -a -f '" +
      (r.dir / "Xauthority").string() + "' -s '-screen 0 1280x800x24' sh run.sh > gui.log 2>&1";
  (void)std::system(cmd.c_str());
  std::ifstream rc(r.dir / "gui.rc");
  rc >> r.exit_code;
  std::ifstream in(r.dir / "stats.json");
  if (in) r.stats = nlohmann::json::parse(in, nullptr, false);
  return r;
}

bool log_has(const nlohmann::json& stats, const std::string& text) {
  for (const auto& l : stats["log"])
    if (l.get<std::string>().find(text) != std::string::npos) return true;
  return false;
}

struct Image {
  int w = 0, h = 0;
  std::vector<unsigned char> px;  // RGBA
};

Image load_png(const fs::path& p) {
  Image img;
  int n = 0;
  unsigned char* data = stbi_load(p.c_str(), &img.w, &img.h, &n, 4);
  if (data) img.px.assign(data, data + static_cast<std::size_t>(img.w) * img.h * 4);
  stbi_image_free(data);
  return img;
}

// Pixels within ±tol of `c` in every channel, inside the plot rectangle
// [x0, y0, x1, y1] the GUI reported (frame-stats "plots").
int count_colour(const Image& img, const nlohmann::json& rect, Rgb c, int tol = 30) {
  const int x0 = std::max(0, static_cast<int>(rect[0].get<double>())),
            y0 = std::max(0, static_cast<int>(rect[1].get<double>())),
            x1 = std::min(img.w, static_cast<int>(rect[2].get<double>())),
            y1 = std::min(img.h, static_cast<int>(rect[3].get<double>()));
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const unsigned char* p = &img.px[4 * (static_cast<std::size_t>(y) * img.w + x)];
      if (std::abs(p[0] - c.r) < tol && std::abs(p[1] - c.g) < tol && std::abs(p[2] - c.b) < tol)
        ++n;
    }
  return n;
}

void print_frame_times(const nlohmann::json& stats) {
  int k = 0;
  for (const auto& j : stats["jobs"])
    std::printf(
        "frame time during job %d: median %.2f ms, p95 %.2f ms, max %.2f ms over %d frames\n", ++k,
        j["median_ms"].get<double>(), j["p95_ms"].get<double>(), j["max_ms"].get<double>(),
        j["frames"].get<int>());
}

// A loopback port with nobody listening: bound, then released.
int closed_port() {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  const bool ok = ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
                  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0;
  ::close(fd);
  return ok ? ntohs(a.sin_port) : -1;
}

// InstrumentForm::State (ui/gui/app_state.hpp) as the stats write it.
constexpr int kConnected = 2, kReplay = 3, kError = 4;

}  // namespace

// The acceptance run. The simulated bench adds 15 ohm in series with the tube,
// which the FE model lacks: the diagnosis must find it. "Measure and update"
// runs twice, so that the second job's frame times are those with every plot
// drawn (the first runs over empty plots); the JSON report is exported in
// between through its button.
TEST(Gui, MeasureAndUpdateUnderXvfb) {
  ScratchCleanup cleanup;
  auto run =
      run_gui("measure",
              "--sim-effects series_resistance=15 --no-calibrate --shots 8 --click 'Measure and update' --click JSON "
              "--click 'Measure and update' --hover 700,90 --wait-job --screenshot screenshot.png");
  ASSERT_EQ(run.exit_code, 0) << "GUI run failed; see " << (run.dir / "gui.log");
  const auto& j = run.stats;
  ASSERT_TRUE(j.is_object()) << "no frame statistics";
  EXPECT_EQ(j["error"], "");
  EXPECT_EQ(j["script_failure"], "");
  EXPECT_EQ(j["clicked"].size(), 3u);
  // The instrument panel identified the simulated instruments.
  EXPECT_EQ(j["instrument_state"], kConnected);
  EXPECT_NE(j["idn_awg"].get<std::string>().find("33522B"), std::string::npos) << j["idn_awg"];
  EXPECT_NE(j["idn_daq"].get<std::string>().find("DSO9104A"), std::string::npos) << j["idn_daq"];

  // A capture was written by the run.
  const fs::path cap = run.dir / j["capture"].get<std::string>();
  ASSERT_TRUE(fs::exists(cap)) << cap;
  EXPECT_EQ(piezo::acq::read_capture(cap).shots.size(), 8u);
  // The parameter table holds updated values.
  ASSERT_EQ(j["params"].size(), 4u);
  for (const auto& p : j["params"])
    EXPECT_NE(p["updated"].get<double>(), p["original"].get<double>()) << p;

  // The diagnosis window showed the verdict and every ranked effect, and the
  // diagnosis added the series resistance the bench has.
  ASSERT_TRUE(j.contains("diagnosis"));
  const auto& d = j["diagnosis"];
  EXPECT_FALSE(j["verdict_shown"].get<std::string>().empty());
  EXPECT_EQ(j["verdict_shown"], d["verdict"]);
  EXPECT_GT(j["effects_shown"].get<int>(), 0);
  EXPECT_EQ(j["effects_shown"].get<std::size_t>(), d["effects"].get<std::size_t>());
  ASSERT_FALSE(d["added"].empty());
  EXPECT_EQ(d["added"][0], "series_resistance");

  // The JSON report exported by its button (from the first job's result).
  std::ifstream report_in(run.dir / "piezobench-report.json");
  ASSERT_TRUE(report_in) << "JSON export missing";
  const auto report = nlohmann::json::parse(report_in);
  EXPECT_EQ(report["parameters"].size(), 4u);
  EXPECT_EQ(report["diagnosis"]["added"][0], "series_resistance");

  print_frame_times(j);
  ASSERT_EQ(j["jobs"].size(), 2u);

  // The screenshot: curves in their plots. Each count must exceed what a
  // legend swatch alone gives (14 × 8 = 112 pixels).
  const Image img = load_png(run.dir / "screenshot.png");
  ASSERT_EQ(img.w, 1280);
  ASSERT_EQ(img.h, 800);
  using namespace piezo::gui;
  const auto& mag = j["plots"]["mag"];
  EXPECT_GT(count_colour(img, mag, rgb_of(kColMeasured)), 400) << "measured |Z| curve missing";
  EXPECT_GT(count_colour(img, mag, rgb_of(kColOriginal)), 400) << "original-model curve missing";
  EXPECT_GT(count_colour(img, mag, rgb_of(kColUpdated)), 400) << "updated-model curve missing";
  // The residual plot: both residual curves, and the shade of the region with
  // the largest share of chi2 (composited over the plot background).
  const auto& res = j["plots"]["residual"];
  EXPECT_GT(count_colour(img, res, rgb_of(kColResidual)), 250) << "residual curve missing";
  EXPECT_GT(count_colour(img, res, rgb_of(kColResidualAfter)), 250)
      << "residual with the effect missing";
  const auto& regions = d["regions"];
  ASSERT_FALSE(regions.empty());
  const auto main_region =
      *std::max_element(regions.begin(), regions.end(), [](const auto& a, const auto& b) {
        return a["share"].template get<double>() < b["share"].template get<double>();
      });
  const ImU32 shade = region_colour(main_region["kind"].get<std::string>());
  EXPECT_GT(count_colour(img, res, blend_over(shade, kColPlotBg), 12), 1500)
      << "shade of " << main_region["name"] << " (" << main_region["kind"] << ") missing";
  fs::copy_file(run.dir / "screenshot.png", fs::path(PIEZO_BINARY_DIR) / "gui-screenshot.png",
                fs::copy_options::overwrite_existing);
}

// A recorded capture replayed through the same pipeline: no instrument, and
// the update moves the parameters towards the simulated tube's.
TEST(Gui, ReplayOfARecordedCapture) {
  ScratchCleanup cleanup;
  const fs::path dir = scratch();
  fs::create_directories(dir);
  const fs::path cap = dir / "recorded.h5";
  const std::string measure =
      std::string("'") + PIEZO_CLI +
      "' measure --instrument sim --sim-isotropic "
      "--sim-set YE11=6.66e10,nu12=0.3333,d31=-210e-12,epsT33_rel=2294 --noise 0.005 "
      "--shots 8 --overwrite --out '" +
      cap.string() + "' > /dev/null 2>&1";
  ASSERT_EQ(std::system(measure.c_str()), 0);
  auto run =
      run_gui("replay", "--replay '" + cap.string() + "' --click 'Replay capture' --wait-job");
  ASSERT_EQ(run.exit_code, 0) << "GUI run failed; see " << (run.dir / "gui.log");
  const auto& j = run.stats;
  EXPECT_EQ(j["error"], "");
  EXPECT_EQ(j["capture"], cap.string());
  EXPECT_EQ(j["instrument_state"], kReplay);
  ASSERT_EQ(j["params"].size(), 4u);
  const auto& ye11 = j["params"][0];
  ASSERT_EQ(ye11["name"], "YE11");
  EXPECT_LT(std::abs(ye11["updated"].get<double>() - 6.66e10),
            std::abs(ye11["original"].get<double>() - 6.66e10));
  EXPECT_FALSE(j["verdict_shown"].get<std::string>().empty());
}

// Limits loaded with 'Limits...' (as `replay --limits`): the replayed
// capture's result is judged and its pass/fail and reasons are shown.
TEST(Gui, LimitsShowPassOrFailWithTheReasons) {
  ScratchCleanup cleanup;
  const fs::path dir = scratch();
  fs::create_directories(dir);
  const fs::path cap = dir / "limits-capture.h5", limits = dir / "limits.toml";
  const std::string measure =
      std::string("'") + PIEZO_CLI +
      "' measure --instrument sim --sim-isotropic "
      "--sim-set YE11=6.66e10,nu12=0.3333,d31=-210e-12,epsT33_rel=2294 --noise 0.005 "
      "--shots 2 --overwrite --out '" +
      cap.string() + "' > /dev/null 2>&1";
  ASSERT_EQ(std::system(measure.c_str()), 0);
  // YE11 must exceed 7e10 (it is ~6.66e10: fail); C^T is in range (pass).
  std::ofstream(limits) << "[[limit]]\nquantity = \"parameters.YE11\"\nunit = \"Pa\"\nmin = 7e10\n"
                           "[[limit]]\nquantity = \"mode_summary.free_capacitance_f\"\nmin = 1e-9\nmax = 1e-7\n";
  auto run = run_gui("limits", "--replay '" + cap.string() + "' --limits '" + limits.string() +
                                   "' --click 'Limits...' --click 'Replay capture' --wait-job");
  ASSERT_EQ(run.exit_code, 0) << "GUI run failed; see " << (run.dir / "gui.log");
  const auto& j = run.stats;
  EXPECT_EQ(j["error"], "");
  EXPECT_EQ(j["limits_status"], "fail");
  ASSERT_EQ(j["limits_reasons"].size(), 1u) << j["limits_reasons"].dump();
  EXPECT_EQ(j["limits_reasons"][0].get<std::string>().rfind("parameters.YE11 = 6.", 0), 0u);
  EXPECT_NE(j["limits_reasons"][0].get<std::string>().find("< min 7e+10 Pa"), std::string::npos);
}

// Errors end in the window with what to do, never in a crash: exit code 2
// (the run's error) with the problem's kind and advice in the statistics.
TEST(Gui, ErrorsAreShownWithWhatToDo) {
  ScratchCleanup cleanup;
  {
    const fs::path dir = scratch();
    fs::create_directories(dir);
    const fs::path bad = dir / "not-a-capture.h5";
    std::ofstream(bad) << "this is not HDF5\n";
    auto run =
        run_gui("bad-file", "--replay '" + bad.string() + "' --click 'Replay capture' --wait-job");
    EXPECT_EQ(run.exit_code, 2) << "see " << (run.dir / "gui.log");
    EXPECT_EQ(run.stats["error_kind"], "file error");
    EXPECT_NE(run.stats["error"].get<std::string>().find("not-a-capture.h5"), std::string::npos);
    EXPECT_FALSE(run.stats["error_advice"].get<std::string>().empty());
    // The GUI opens on the CLI's defaults (issue 41 item 5): `demo`'s shots,
    // fixture standards, held-out chirp and noise.
    const piezo::jobs::DemoRequest demo;
    EXPECT_EQ(run.stats["plan"]["shots"], demo.shots);
    EXPECT_EQ(run.stats["plan"]["calibration"], !demo.no_calibrate);
    EXPECT_EQ(run.stats["plan"]["heldout"], true);
    EXPECT_EQ(run.stats["plan"]["noise"], demo.noise);
  }
  {
    const int port = closed_port();
    ASSERT_GT(port, 0);
    auto run = run_gui("no-instrument", "--instrument tcp://127.0.0.1:" + std::to_string(port) +
                                            " --click 'Measure and update' --wait-job");
    EXPECT_EQ(run.exit_code, 2) << "see " << (run.dir / "gui.log");
    EXPECT_EQ(run.stats["error_kind"], "connection error");
    EXPECT_FALSE(run.stats["error_advice"].get<std::string>().empty());
    EXPECT_EQ(run.stats["instrument_state"], kError);
    EXPECT_FALSE(run.stats["instrument_error"].get<std::string>().empty());
  }
}

// Cancel during a long acquisition (64 shots, clicked a few frames after the
// start): the run ends without an error, before the update, and the capture
// keeps what was acquired.
TEST(Gui, CancelStopsTheRun) {
  ScratchCleanup cleanup;
  auto run = run_gui("cancel", "--shots 64 --click 'Measure and update' --click Cancel --wait-job");
  ASSERT_EQ(run.exit_code, 0) << "GUI run failed; see " << (run.dir / "gui.log");
  const auto& j = run.stats;
  EXPECT_EQ(j["clicked"].size(), 2u);
  EXPECT_EQ(j["error"], "");
  EXPECT_TRUE(log_has(j, "job cancelled"));
  EXPECT_TRUE(j["params"].empty());
  const fs::path cap = run.dir / j["capture"].get<std::string>();
  ASSERT_TRUE(fs::exists(cap)) << cap;
  // A capture cancelled before its first shot holds none and reads as invalid.
  piezo::acq::ReadOptions meta;
  meta.load_samples = false;
  try {
    EXPECT_LT(piezo::acq::read_capture(cap, meta).shots.size(), 64u);
  } catch (const piezo::acq::CaptureError& e) {
    EXPECT_NE(std::string(e.what()).find("no shots"), std::string::npos) << e.what();
  }
}
