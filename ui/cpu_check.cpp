// The instruction set this program was built for (CMakeLists.txt: PIEZO_MARCH,
// docs/build-and-test.md), checked before anything else of it runs: a build
// for x86-64-v3 (AVX2, FMA, BMI2) taken to an older CPU would otherwise die of an
// illegal instruction at its first vector loop, with no word of why. This
// file alone is compiled for the baseline x86-64 (ui/CMakeLists.txt), and its
// check runs as the first static constructor (priority 101), before Eigen's
// or any other static object's: it says what is wrong and what to do, and
// exits with 1 (the commands' internal-error code, ui/cli/cli_common.hpp).
#if defined(PIEZO_BUILT_FOR_MARCH) && defined(__GNUC__) && defined(__x86_64__)
#include <unistd.h>

namespace {

__attribute__((constructor(101))) void check_instruction_set() {
  __builtin_cpu_init();
  if (__builtin_cpu_supports(PIEZO_BUILT_FOR_MARCH)) return;
  static const char kMessage[] =
      "piezobench: this program was built for the " PIEZO_BUILT_FOR_MARCH
      " instruction set, which this CPU does not have.\n"
      "  Build it on this machine (make demo / make test choose the CPU's set), or configure with\n"
      "  -DPIEZO_MARCH=baseline for a program that runs on any x86-64 CPU.\n";
  // (write(2): nothing of the C++ runtime is needed, nor initialised yet.)
  const ssize_t ignored = write(2, kMessage, sizeof kMessage - 1);
  (void)ignored;
  _exit(1);
}

}  // namespace
#endif
