// main() for a fuzz harness built without libFuzzer (gcc, the normal build):
// replays every file of the seed corpus and of the regression directory, then
// runs deterministic random mutations of them (bit flips, byte edits, inserts,
// deletes, duplications, dictionary tokens, splices) for a bounded time and a
// bounded count. Exit status 0: no finding; 1: a finding (the input is saved
// and the command to replay it printed); 2: usage error.
//
//   fuzz_<name> [--seconds S] [--runs N] [--seed K] [--max-len B] [--timeout S]
//               [--malloc-limit-mb M] [--dict FILE] [--artifact-dir DIR] [-v] [FILE|DIR ...]
//
// Findings: a crash (signal), an uncaught exception, an input running longer
// than --timeout, and (builds without sanitizers) one operator new of more
// than --malloc-limit-mb, as libFuzzer's -malloc_limit_mb.
//
// Without FILE/DIR arguments it uses the harness's corpus and regression
// directories (compiled in); with them, only those (a single file: replay it).
#include <cxxabi.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <new>
#include <random>
#include <string>
#include <typeinfo>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

#ifndef PIEZO_FUZZ_NAME
#define PIEZO_FUZZ_NAME "harness"
#endif

#if defined(__SANITIZE_ADDRESS__)
#define PIEZO_FUZZ_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PIEZO_FUZZ_SANITIZED 1
#endif
#endif
#ifdef PIEZO_FUZZ_SANITIZED
extern "C" void __sanitizer_set_death_callback(void (*)(void));
#endif

namespace fs = std::filesystem;

namespace {

using Bytes = std::vector<std::uint8_t>;

// ------------------------------------------------------------ the input at risk
// Kept where a signal handler can reach it: on a crash it is written to disk
// with async-signal-safe calls only.
const std::uint8_t* g_data = nullptr;
std::size_t g_size = 0;
char g_artifact[4096] = "";  // path the current input is saved under on a finding
volatile sig_atomic_t g_running = 0;

std::uint64_t fnv1a(const std::uint8_t* d, std::size_t n) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < n; ++i) h = (h ^ d[i]) * 1099511628211ull;
  return h;
}

void write_str(const char* s) {
  ssize_t r = ::write(2, s, std::strlen(s));
  (void)r;
}

void save_current_input() {
  if (!g_running || !g_artifact[0]) return;
  int fd = ::open(g_artifact, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) return;
  std::size_t off = 0;
  while (off < g_size) {
    ssize_t w = ::write(fd, g_data + off, g_size - off);
    if (w <= 0) break;
    off += static_cast<std::size_t>(w);
  }
  ::close(fd);
  write_str("\nfuzz_" PIEZO_FUZZ_NAME ": FINDING; input saved as ");
  write_str(g_artifact);
  write_str("\n  replay: fuzz_" PIEZO_FUZZ_NAME " ");
  write_str(g_artifact);
  write_str("\n");
  g_running = 0;
}

void on_fatal_signal(int sig) {
  if (g_running) {
    const char* what = sig == SIGALRM   ? "timeout (one input ran too long)"
                       : sig == SIGABRT ? "abort (a failed check or std::terminate)"
                       : sig == SIGSEGV ? "SIGSEGV"
                       : sig == SIGBUS  ? "SIGBUS"
                       : sig == SIGFPE  ? "SIGFPE"
                                        : "SIGILL";
    write_str("\nfuzz_" PIEZO_FUZZ_NAME ": FINDING: ");
    write_str(what);
    write_str("\n");
  }
  save_current_input();
  ::signal(sig == SIGALRM ? SIGABRT : sig, SIG_DFL);
  ::raise(sig == SIGALRM ? SIGABRT : sig);
}

#ifdef PIEZO_FUZZ_SANITIZED
void on_sanitizer_death() { save_current_input(); }
#endif

void install_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_fatal_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND;
  ::sigaction(SIGABRT, &sa, nullptr);
  ::sigaction(SIGALRM, &sa, nullptr);
#ifdef PIEZO_FUZZ_SANITIZED
  // The sanitizer reports SEGV and friends itself; it calls us before exiting.
  __sanitizer_set_death_callback(on_sanitizer_death);
#else
  for (int s : {SIGSEGV, SIGBUS, SIGFPE, SIGILL}) ::sigaction(s, &sa, nullptr);
#endif
}

// ------------------------------------------------------------ allocation limit
// One allocation beyond the limit is a finding (a length taken from the input
// and trusted); reported before the memory is touched. Not with sanitizers:
// they replace the allocator themselves.
std::size_t g_malloc_limit = 0;  // 0: off (until main() sets it)

#ifndef PIEZO_FUZZ_SANITIZED
void* checked_alloc(std::size_t n) {
  if (g_malloc_limit && n > g_malloc_limit && g_running) {
    char msg[128];
    std::snprintf(msg, sizeof msg, "\nfuzz_" PIEZO_FUZZ_NAME ": FINDING: one allocation of %zu bytes (limit %zu)\n",
                  n, g_malloc_limit);
    write_str(msg);
    save_current_input();
    std::abort();
  }
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
#endif

std::string demangle(const char* name) {
  int st = 0;
  char* d = abi::__cxa_demangle(name, nullptr, nullptr, &st);
  std::string out = st == 0 && d ? d : name;
  std::free(d);
  return out;
}

// ------------------------------------------------------------ options
struct Options {
  double seconds = 3.0;
  std::uint64_t runs = 1'000'000;
  std::uint64_t seed = 1;
  std::size_t max_len = 4096;
  unsigned timeout_s = 20;
  std::size_t malloc_limit_mb = 256;
  std::string dict;
  fs::path artifact_dir = ".";
  bool verbose = false;
  std::vector<fs::path> inputs;
};

[[noreturn]] void usage(const char* why) {
  std::fprintf(stderr,
               "fuzz_%s: %s\nusage: fuzz_%s [--seconds S] [--runs N] [--seed K] [--max-len B] "
               "[--timeout S] [--malloc-limit-mb M] [--dict FILE] [--artifact-dir DIR] [-v] "
               "[FILE|DIR ...]\n",
               PIEZO_FUZZ_NAME, why, PIEZO_FUZZ_NAME);
  std::exit(2);
}

Options parse_args(int argc, char** argv) {
  Options o;
#ifdef PIEZO_FUZZ_DICT
  o.dict = PIEZO_FUZZ_DICT;
#endif
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage(("missing value after " + a).c_str());
      return argv[++i];
    };
    try {
      if (a == "--seconds") o.seconds = std::stod(value());
      else if (a == "--runs") o.runs = std::stoull(value());
      else if (a == "--seed") o.seed = std::stoull(value());
      else if (a == "--max-len") o.max_len = std::stoul(value());
      else if (a == "--timeout") o.timeout_s = static_cast<unsigned>(std::stoul(value()));
      else if (a == "--malloc-limit-mb") o.malloc_limit_mb = std::stoul(value());
      else if (a == "--dict") o.dict = value();
      else if (a == "--artifact-dir") o.artifact_dir = value();
      else if (a == "-v" || a == "--verbose") o.verbose = true;
      else if (a == "-h" || a == "--help") usage("help");
      else if (a.starts_with("-")) usage(("unknown option " + a).c_str());
      else o.inputs.emplace_back(a);
    } catch (const std::logic_error&) {
      usage(("bad value for " + a).c_str());
    }
  }
  if (o.inputs.empty()) {
#ifdef PIEZO_FUZZ_CORPUS_DIR
    o.inputs.emplace_back(PIEZO_FUZZ_CORPUS_DIR);
#endif
#ifdef PIEZO_FUZZ_REGRESSION_DIR
    o.inputs.emplace_back(PIEZO_FUZZ_REGRESSION_DIR);
#endif
  }
  if (o.max_len == 0) usage("--max-len must be positive");
  return o;
}

// ------------------------------------------------------------ corpus and dictionary
struct Entry {
  fs::path path;
  Bytes bytes;
};

Bytes read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}

std::vector<Entry> load_inputs(const std::vector<fs::path>& inputs) {
  std::vector<Entry> out;
  for (const auto& in : inputs) {
    std::error_code ec;
    if (fs::is_directory(in, ec)) {
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(in, ec))
        if (e.is_regular_file() && e.path().filename().string()[0] != '.' &&
            e.path().filename() != "README.md")
          files.push_back(e.path());
      std::sort(files.begin(), files.end());  // deterministic order
      for (auto& f : files) out.push_back({f, read_file(f)});
    } else if (fs::is_regular_file(in, ec)) {
      out.push_back({in, read_file(in)});
    } else if (!fs::exists(in, ec)) {
      std::fprintf(stderr, "fuzz_%s: note: %s does not exist (skipped)\n", PIEZO_FUZZ_NAME,
                   in.c_str());
    }
  }
  return out;
}

// libFuzzer dictionary format: one token per line, `name="value"` or
// `"value"`, with \\, \" and \xNN escapes; '#' starts a comment line.
std::vector<Bytes> load_dict(const std::string& path) {
  std::vector<Bytes> out;
  if (path.empty()) return out;
  std::ifstream in(path);
  if (!in) {
    std::fprintf(stderr, "fuzz_%s: cannot read dictionary %s\n", PIEZO_FUZZ_NAME, path.c_str());
    std::exit(2);
  }
  std::string line;
  while (std::getline(in, line)) {
    auto q = line.find('"');
    auto e = line.rfind('"');
    if (line.empty() || line[0] == '#' || q == std::string::npos || e <= q) continue;
    Bytes tok;
    for (std::size_t i = q + 1; i < e; ++i) {
      if (line[i] == '\\' && i + 1 < e) {
        char c = line[++i];
        if (c == 'x' && i + 2 < e) {
          tok.push_back(static_cast<std::uint8_t>(std::stoi(line.substr(i + 1, 2), nullptr, 16)));
          i += 2;
        } else {
          tok.push_back(static_cast<std::uint8_t>(c));
        }
      } else {
        tok.push_back(static_cast<std::uint8_t>(line[i]));
      }
    }
    if (!tok.empty()) out.push_back(std::move(tok));
  }
  return out;
}

// ------------------------------------------------------------ mutations
class Mutator {
 public:
  Mutator(std::uint64_t seed, std::size_t max_len, std::vector<Bytes> dict)
      : rng_(seed), max_len_(max_len), dict_(std::move(dict)) {}

  std::size_t below(std::size_t n) { return n == 0 ? 0 : std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_); }

  Bytes mutate(const Bytes& base, const std::vector<const Bytes*>& pool) {
    Bytes b = base;
    const std::size_t n_ops = 1 + below(std::min<std::size_t>(6, 1 + below(6)));
    for (std::size_t k = 0; k < n_ops; ++k) one(b, pool);
    if (b.size() > max_len_) b.resize(max_len_);
    return b;
  }

 private:
  void one(Bytes& b, const std::vector<const Bytes*>& pool) {
    static constexpr std::uint8_t kInteresting[] = {0, 1, 0x7f, 0x80, 0xff, 0xfe, 16, 32, 64, 100,
                                                    '0', '9', '#', '\n', ',', '-', '.', 'e'};
    switch (below(b.empty() ? 2 : 11)) {
      case 0: {  // insert random bytes
        const std::size_t at = below(b.size() + 1), len = 1 + below(8);
        Bytes r(len);
        for (auto& x : r) x = static_cast<std::uint8_t>(below(256));
        b.insert(b.begin() + static_cast<std::ptrdiff_t>(at), r.begin(), r.end());
        break;
      }
      case 1: {  // insert a dictionary token (or an interesting byte)
        const std::size_t at = below(b.size() + 1);
        if (!dict_.empty() && below(4) != 0) {
          const Bytes& t = dict_[below(dict_.size())];
          b.insert(b.begin() + static_cast<std::ptrdiff_t>(at), t.begin(), t.end());
        } else {
          b.insert(b.begin() + static_cast<std::ptrdiff_t>(at), kInteresting[below(sizeof kInteresting)]);
        }
        break;
      }
      case 2:  // flip a bit
        b[below(b.size())] ^= static_cast<std::uint8_t>(1u << below(8));
        break;
      case 3:  // set a byte
        b[below(b.size())] = static_cast<std::uint8_t>(below(256));
        break;
      case 4:  // an interesting byte
        b[below(b.size())] = kInteresting[below(sizeof kInteresting)];
        break;
      case 5: {  // small arithmetic on a byte
        auto& x = b[below(b.size())];
        x = static_cast<std::uint8_t>(x + (below(2) ? 1 : -1) * static_cast<int>(1 + below(8)));
        break;
      }
      case 6: {  // delete a range
        const std::size_t at = below(b.size()), len = 1 + below(std::min<std::size_t>(16, b.size() - at));
        b.erase(b.begin() + static_cast<std::ptrdiff_t>(at), b.begin() + static_cast<std::ptrdiff_t>(at + len));
        break;
      }
      case 7: {  // duplicate a range in place
        const std::size_t at = below(b.size()), len = 1 + below(std::min<std::size_t>(32, b.size() - at));
        Bytes r(b.begin() + static_cast<std::ptrdiff_t>(at), b.begin() + static_cast<std::ptrdiff_t>(at + len));
        b.insert(b.begin() + static_cast<std::ptrdiff_t>(below(b.size() + 1)), r.begin(), r.end());
        break;
      }
      case 8: {  // overwrite with a copy of another range
        const std::size_t from = below(b.size()), to = below(b.size());
        const std::size_t len = 1 + below(std::min(b.size() - from, b.size() - to));
        std::memmove(b.data() + to, b.data() + from, len);
        break;
      }
      case 9: {  // splice: our head, another input's tail
        if (pool.empty()) break;
        const Bytes& o = *pool[below(pool.size())];
        const std::size_t cut = below(b.size() + 1), from = below(o.size() + 1);
        b.resize(cut);
        b.insert(b.end(), o.begin() + static_cast<std::ptrdiff_t>(from), o.end());
        break;
      }
      default: {  // overwrite with a dictionary token
        if (dict_.empty()) break;
        const Bytes& t = dict_[below(dict_.size())];
        const std::size_t at = below(b.size());
        for (std::size_t i = 0; i < t.size() && at + i < b.size(); ++i) b[at + i] = t[i];
        break;
      }
    }
  }

  std::mt19937_64 rng_;
  std::size_t max_len_;
  std::vector<Bytes> dict_;
};

// ------------------------------------------------------------ running one input
bool run_one(const Bytes& in, const std::string& label, const Options& o) {
  // The buffer is copied so that a harness reading past the end is caught by
  // sanitizers exactly as under libFuzzer (heap block of the exact size).
  std::unique_ptr<std::uint8_t[]> copy(new std::uint8_t[in.size() ? in.size() : 1]);
  if (!in.empty()) std::memcpy(copy.get(), in.data(), in.size());  // an empty input has no data()
  g_data = copy.get();
  g_size = in.size();
  std::snprintf(g_artifact, sizeof g_artifact, "%s/fuzz-%s-finding-%016llx", o.artifact_dir.c_str(),
                PIEZO_FUZZ_NAME, static_cast<unsigned long long>(fnv1a(in.data(), in.size())));
  g_running = 1;
  ::alarm(o.timeout_s);
  try {
    LLVMFuzzerTestOneInput(copy.get(), in.size());
  } catch (const std::exception& e) {
    ::alarm(0);
    std::fprintf(stderr, "\nfuzz_%s: FINDING: uncaught %s: %s\n  input: %s\n", PIEZO_FUZZ_NAME,
                 demangle(typeid(e).name()).c_str(), e.what(), label.c_str());
    save_current_input();
    return false;
  } catch (...) {
    ::alarm(0);
    std::fprintf(stderr, "\nfuzz_%s: FINDING: uncaught exception of unknown type\n  input: %s\n",
                 PIEZO_FUZZ_NAME, label.c_str());
    save_current_input();
    return false;
  }
  ::alarm(0);
  g_running = 0;
  return true;
}

}  // namespace

#ifndef PIEZO_FUZZ_SANITIZED
void* operator new(std::size_t n) { return checked_alloc(n); }
void* operator new[](std::size_t n) { return checked_alloc(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
#endif

int main(int argc, char** argv) {
  const Options o = parse_args(argc, argv);
  install_handlers();
  g_malloc_limit = o.malloc_limit_mb << 20;
  std::error_code ec;
  fs::create_directories(o.artifact_dir, ec);

  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Entry> corpus = load_inputs(o.inputs);
  for (const auto& e : corpus) {
    if (o.verbose) std::fprintf(stderr, "fuzz_%s: replay %s\n", PIEZO_FUZZ_NAME, e.path.c_str());
    if (!run_one(e.bytes, e.path.string(), o)) return 1;
  }
  const double replay_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // A single file given on the command line: a replay, no mutations.
  const bool replay_only = o.inputs.size() == 1 && fs::is_regular_file(o.inputs[0], ec);

  std::uint64_t runs = 0;
  double fuzz_s = 0;
  if (!replay_only && o.seconds > 0 && o.runs > 0) {
    Mutator m(o.seed, o.max_len, load_dict(o.dict));
    // Pool: the corpus plus a bounded, randomly replaced sample of mutants that
    // passed, so mutations can walk further than one step from a seed.
    std::vector<Bytes> grown;
    std::vector<const Bytes*> pool;
    auto rebuild = [&] {
      pool.clear();
      for (auto& e : corpus) pool.push_back(&e.bytes);
      for (auto& g : grown) pool.push_back(&g);
    };
    rebuild();
    if (pool.empty()) {
      grown.push_back(Bytes{});
      rebuild();
    }
    const auto start = std::chrono::steady_clock::now();
    const auto deadline = start + std::chrono::duration<double>(o.seconds);
    while (runs < o.runs) {
      if ((runs & 15) == 0 && std::chrono::steady_clock::now() >= deadline) break;
      Bytes in = m.mutate(*pool[m.below(pool.size())], pool);
      ++runs;
      if (!run_one(in, "mutant #" + std::to_string(runs) + " (seed " + std::to_string(o.seed) + ")", o))
        return 1;
      if (m.below(8) == 0) {
        if (grown.size() < 256) grown.push_back(std::move(in));
        else grown[m.below(grown.size())] = std::move(in);
        rebuild();
      }
    }
    fuzz_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  std::printf("fuzz_%s: %zu corpus/regression inputs replayed in %.2f s; %llu mutants in %.2f s "
              "(%.0f exec/s, seed %llu); no finding\n",
              PIEZO_FUZZ_NAME, corpus.size(), replay_s, static_cast<unsigned long long>(runs), fuzz_s,
              fuzz_s > 0 ? static_cast<double>(runs) / fuzz_s : 0.0,
              static_cast<unsigned long long>(o.seed));
  return 0;
}
