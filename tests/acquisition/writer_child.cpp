// Test helper process: writes a capture shot by shot and reports each
// completed shot on stdout ("done K"), so that a test can SIGKILL it mid-shot.
// Usage: capture_writer_child OUT.h5 SHOTS SAMPLES
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "acquisition/capture_file.hpp"
#include "tests/acquisition/writer_child_data.hpp"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s OUT.h5 SHOTS SAMPLES\n", argv[0]);
    return 2;
  }
  const int shots = std::atoi(argv[2]);
  const std::size_t n = std::strtoul(argv[3], nullptr, 10);
  piezo::acq::Setup setup;
  setup.divider_r1_ohm = 3140;
  piezo::acq::WriterOptions opt;
  opt.overwrite = true;
  piezo::acq::CaptureWriter w(argv[1], setup, opt);
  for (int k = 0; k < shots; ++k) {
    w.append(piezo::test::child_shot(k, n));
    std::printf("done %d\n", k);
    std::fflush(stdout);
  }
  w.close();
  std::printf("closed\n");
  return 0;
}
