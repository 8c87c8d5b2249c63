// A writer process killed with SIGKILL in the middle of a shot leaves either
// no file under the final name or a file holding every completed shot; the
// .partial file holds every completed shot (no acquired data lost).
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "acquisition/capture_file.hpp"
#include "tests/acquisition/writer_child_data.hpp"

extern char** environ;
namespace fs = std::filesystem;
using namespace piezo;

namespace {

struct Child {
  pid_t pid = -1;
  FILE* out = nullptr;
};

Child spawn_writer(const fs::path& file, int shots, std::size_t n) {
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("pipe");
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_adddup2(&fa, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_addclose(&fa, fds[0]);
  std::string exe = CAPTURE_WRITER_CHILD, f = file.string(), s = std::to_string(shots),
              ns = std::to_string(n);
  char* argv[] = {exe.data(), f.data(), s.data(), ns.data(), nullptr};
  Child c;
  if (posix_spawn(&c.pid, exe.c_str(), &fa, nullptr, argv, environ) != 0)
    throw std::runtime_error("posix_spawn " + exe);
  posix_spawn_file_actions_destroy(&fa);
  close(fds[1]);
  c.out = fdopen(fds[0], "r");
  return c;
}

// Reads "done K" lines until shot `k` is reported; returns false on EOF.
bool wait_for_shot(Child& c, int k) {
  char line[64];
  while (std::fgets(line, sizeof line, c.out)) {
    int got = -1;
    if (std::sscanf(line, "done %d", &got) == 1 && got >= k) return true;
  }
  return false;
}

void expect_shots_intact(const acq::Capture& cap, std::size_t n) {
  for (std::size_t k = 0; k < cap.shots.size(); ++k) {
    auto want = test::child_shot(static_cast<int>(k), n);
    ASSERT_EQ(cap.shots[k].v1, want.v1) << "shot " << k;
    ASSERT_EQ(cap.shots[k].v2, want.v2) << "shot " << k;
  }
}

}  // namespace

TEST(CaptureCrash, SigkillMidShotLosesNoCompletedShot) {
  const fs::path dir = fs::temp_directory_path() / ("piezobench-crash-" + std::to_string(getpid()));
  fs::create_directories(dir);
  constexpr std::size_t kN = 400000;  // ~6 MB per shot: the kill lands inside a write
  const int delays_us[] = {0, 500, 2000, 5000, 10000, 20000, 40000};
  int trial = 0;
  for (int delay : delays_us) {
    const fs::path file = dir / ("kill" + std::to_string(trial++) + ".h5");
    Child c = spawn_writer(file, 1000, kN);
    ASSERT_TRUE(wait_for_shot(c, 1)) << "writer ended early";
    std::this_thread::sleep_for(std::chrono::microseconds(delay));
    kill(c.pid, SIGKILL);
    int status = 0;
    waitpid(c.pid, &status, 0);
    // Shots reported after our wait are also complete; drain them.
    int completed = 2;
    char line[64];
    while (std::fgets(line, sizeof line, c.out)) {
      int got = -1;
      if (std::sscanf(line, "done %d", &got) == 1) completed = got + 1;
    }
    fclose(c.out);
    ASSERT_TRUE(WIFSIGNALED(status)) << "delay " << delay << " us";

    if (fs::exists(file)) {  // final name present: must be complete
      auto cap = acq::read_capture(file);
      expect_shots_intact(cap, kN);
    }
    const fs::path partial = acq::partial_path_for(file);
    ASSERT_TRUE(fs::exists(partial)) << "delay " << delay << " us";
    acq::Capture cap;
    ASSERT_NO_THROW(cap = acq::read_capture(partial)) << "delay " << delay << " us";
    EXPECT_GE(cap.shots.size(), static_cast<std::size_t>(completed)) << "delay " << delay;
    EXPECT_LE(cap.shots.size(), static_cast<std::size_t>(completed) + 1) << "delay " << delay;
    expect_shots_intact(cap, kN);
  }
  fs::remove_all(dir);
}

TEST(CaptureCrash, CleanExitRenamesToFinalName) {
  const fs::path dir = fs::temp_directory_path() / ("piezobench-clean-" + std::to_string(getpid()));
  fs::create_directories(dir);
  Child c = spawn_writer(dir / "ok.h5", 3, 1000);
  char line[64];
  while (std::fgets(line, sizeof line, c.out)) {
  }
  fclose(c.out);
  int status = 0;
  waitpid(c.pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_FALSE(fs::exists(acq::partial_path_for(dir / "ok.h5")));
  auto cap = acq::read_capture(dir / "ok.h5");
  EXPECT_EQ(cap.shots.size(), 3u);
  expect_shots_intact(cap, 1000);
  fs::remove_all(dir);
}
