// The bench application under Xvfb (Mesa llvmpipe): start it on the simulated
// bench, click "Measure and update" through injected input, wait for the end,
// then check the capture, the parameter table and the screenshot (known plot
// colours inside the plot areas), and report the frame times during the job.
#include <gtest/gtest.h>
#include <stb_image.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "acquisition/capture_file.hpp"

namespace fs = std::filesystem;

namespace {
struct Rgb {
  int r, g, b;
};
// Counts pixels close to a colour inside a rectangle of the image.
int count_colour(const unsigned char* px, int w, int x0, int y0, int x1, int y1, Rgb c) {
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const unsigned char* p = px + 4 * (y * w + x);
      if (std::abs(p[0] - c.r) < 30 && std::abs(p[1] - c.g) < 30 && std::abs(p[2] - c.b) < 30) ++n;
    }
  return n;
}
}  // namespace

TEST(Gui, MeasureAndUpdateUnderXvfb) {
  const fs::path dir = fs::temp_directory_path() / ("piezobench-gui-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path png = dir / "screenshot.png", stats = dir / "stats.json";
  // Under `make test-asan`, LeakSanitizer reports blocks that Mesa's
  // dlopen'ed llvmpipe driver never frees (frames in "<unknown module>");
  // leak checks of our own code run in every other test, so they are off for
  // this process only (ASan's other checks stay on).
  std::string cmd = "cd '" + dir.string() + "' && ASAN_OPTIONS=detect_leaks=0 xvfb-run -a -s '-screen 0 1280x800x24' '" PIEZO_GUI
                    "' --click 'Measure and update' --wait-job --screenshot '" + png.string() +
                    "' --frame-stats '" + stats.string() + "' --timeout 240 > gui.log 2>&1";
  int rc = std::system(cmd.c_str());
  ASSERT_EQ(rc, 0) << "GUI run failed; see " << (dir / "gui.log");

  std::ifstream in(stats);
  auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["error"], "");
  // A capture was written by the run.
  fs::path cap = dir / j["capture"].get<std::string>();
  ASSERT_TRUE(fs::exists(cap)) << cap;
  EXPECT_GE(piezo::acq::read_capture(cap).shots.size(), 1u);
  // The parameter table holds updated values.
  ASSERT_FALSE(j["params"].empty());
  for (const auto& p : j["params"]) EXPECT_NE(p["updated"].get<double>(), p["original"].get<double>()) << p;
  // Frame time while the job ran (reported; the 33 ms target is checked in the note, not here).
  std::printf("frame time during the job: median %.2f ms, p95 %.2f ms, max %.2f ms over %d frames\n",
              j["median_ms"].get<double>(), j["p95_ms"].get<double>(), j["max_ms"].get<double>(),
              j["frames_during_job"].get<int>());

  int w = 0, h = 0, n = 0;
  unsigned char* px = stbi_load(png.c_str(), &w, &h, &n, 4);
  ASSERT_NE(px, nullptr);
  ASSERT_EQ(w, 1280);
  ASSERT_EQ(h, 800);
  // The |Z| plot occupies the upper right: measured (amber), original (blue), updated (green).
  const int x0 = 460, x1 = 1255, y0 = 80, y1 = 230;
  EXPECT_GT(count_colour(px, w, x0, y0, x1, y1, {255, 200, 40}), 200) << "measured |Z| curve missing";
  EXPECT_GT(count_colour(px, w, x0, y0, x1, y1, {80, 160, 255}), 200) << "original-model curve missing";
  EXPECT_GT(count_colour(px, w, x0, y0, x1, y1, {60, 220, 120}), 200) << "updated-model curve missing";
  stbi_image_free(px);
  fs::copy_file(png, fs::path(PIEZO_BINARY_DIR) / "gui-screenshot.png", fs::copy_options::overwrite_existing);
}
