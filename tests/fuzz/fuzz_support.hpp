#pragma once
// Shared by the fuzz harnesses (tests/fuzz/fuzz_*.cpp): the invariant check
// that turns a broken promise into a finding, a byte reader that turns fuzz
// bytes into decisions (a small FuzzedDataProvider that also builds with gcc),
// and a per-process temporary directory for harnesses that need real files.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <system_error>

// A violated invariant is a finding: say which, then abort (libFuzzer and the
// standalone driver both treat SIGABRT as a crash and keep the input).
#define FUZZ_CHECK(cond, ...)                                                           \
  do {                                                                                 \
    if (!(cond)) {                                                                     \
      std::fprintf(stderr, "\nFUZZ FINDING: invariant violated: %s (%s:%d)\n  ", #cond, \
                   __FILE__, __LINE__);                                                \
      std::fprintf(stderr, __VA_ARGS__);                                               \
      std::fprintf(stderr, "\n");                                                      \
      std::abort();                                                                    \
    }                                                                                  \
  } while (0)

namespace piezo::fuzz {

// Reads decisions from the front of the input; past the end every read is 0,
// so any input, however short, is a complete recipe.
class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : p_(data), n_(size) {}

  bool empty() const { return i_ >= n_; }
  std::size_t remaining() const { return empty() ? 0 : n_ - i_; }

  std::uint8_t u8() { return i_ < n_ ? p_[i_++] : 0; }
  std::uint16_t u16() { return static_cast<std::uint16_t>(u8() | (u8() << 8)); }
  std::uint32_t u32() { return u16() | (std::uint32_t{u16()} << 16); }
  std::uint64_t u64() { return u32() | (std::uint64_t{u32()} << 32); }
  bool flag() { return u8() & 1; }
  // A value in [0, n), n >= 1.
  std::size_t pick(std::size_t n) { return n <= 256 ? u8() % n : u16() % n; }
  double raw_double() {
    std::uint64_t b = u64();
    double d;
    std::memcpy(&d, &b, sizeof d);
    return d;
  }
  // Up to `max` bytes, length first.
  std::string str(std::size_t max) {
    std::size_t len = pick(max + 1);
    std::string s;
    for (std::size_t k = 0; k < len && !empty(); ++k) s += static_cast<char>(u8());
    return s;
  }
  // Everything not read yet.
  std::span<const std::uint8_t> rest() {
    std::span<const std::uint8_t> r(p_ + (empty() ? n_ : i_), remaining());
    i_ = n_;
    return r;
  }

 private:
  const std::uint8_t* p_;
  std::size_t n_;
  std::size_t i_ = 0;
};

inline bool all_finite(std::span<const double> v) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

// One temporary directory per process, created on first use, removed with
// everything in it when the process exits normally. (A crashing run leaves
// it behind; its name says which harness and process made it.)
class ProcessTempDir {
 public:
  static const std::filesystem::path& get(const char* harness) {
    static ProcessTempDir d(harness);
    return d.path_;
  }
  ProcessTempDir(const ProcessTempDir&) = delete;
  ProcessTempDir& operator=(const ProcessTempDir&) = delete;
  ~ProcessTempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }

 private:
  explicit ProcessTempDir(const char* harness) {
    // tmpfs when there is one: the harness writes a file per input.
    std::filesystem::path base = "/dev/shm";
    if (const char* t = std::getenv("TMPDIR"); t && *t) base = t;
    if (::access(base.c_str(), W_OK) != 0) base = std::filesystem::temp_directory_path();
    std::string templ = (base / (std::string("piezo-fuzz-") + harness + "-XXXXXX")).string();
    if (!::mkdtemp(templ.data())) {
      std::perror("fuzz: mkdtemp");
      std::abort();
    }
    path_ = templ;
  }
  std::filesystem::path path_;
};

}  // namespace piezo::fuzz
