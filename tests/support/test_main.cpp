// main() of every GoogleTest program of the suite: the tests run with their
// own scratch folder as the temporary directory (TMPDIR, which
// std::filesystem::temp_directory_path() and the CLI processes the tests start
// both follow), removed when the program ends, so a run of the suite leaves
// nothing behind in /tmp. PIEZO_KEEP_TEST_TMP=1 keeps it (its path is printed)
// to look into a failure.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  std::error_code ec;
  const fs::path base = fs::temp_directory_path(ec);
  fs::path scratch;
  if (!ec) {
    scratch = base / ("piezobench-test-" + std::to_string(::getpid()));
    fs::create_directories(scratch, ec);
    if (!ec) ::setenv("TMPDIR", scratch.c_str(), 1);
    else scratch.clear();
  }
  const int rc = RUN_ALL_TESTS();
  if (!scratch.empty()) {
    const char* keep = std::getenv("PIEZO_KEEP_TEST_TMP");
    if (keep && *keep && std::string(keep) != "0")
      std::fprintf(stderr, "test scratch folder kept: %s\n", scratch.c_str());
    else
      fs::remove_all(scratch, ec);
  }
  return rc;
}
