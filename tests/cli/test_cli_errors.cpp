// Issue 41 item 6: errors that name the next step, run through the built CLI —
// an instrument that refuses the connection (exit 2, what to check, how to
// start the simulated one), an existing --out (named --overwrite, the file
// untouched), an impedance analyzer's file given as a capture (pointed to
// `figures`), no internal function names, "did you mean" for a mistyped
// command or option, and `replay --jobs` defaulting to the cores. Also the
// nearest-name rule itself (ui/cli/suggest.hpp).
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "tests/support/run_cli.hpp"
#include "ui/cli/suggest.hpp"

namespace fs = std::filesystem;
using piezo::test::run_cli;

namespace {

const std::string kFixtures = std::string(PIEZO_SOURCE_DIR) + "/fixtures/";

fs::path tmp_dir() {
  auto d = fs::temp_directory_path() / ("piezobench-errors-" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

struct TmpCleanup {
  ~TmpCleanup() {
    std::error_code ec;
    fs::remove_all(tmp_dir(), ec);
  }
};

// A loopback port nothing listens on: bound by the kernel's choice, then closed.
int closed_port() {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

}  // namespace

TEST(CliErrors, RefusedConnectionNamesTheNextStepAndIsExitTwo) {
  TmpCleanup cleanup;
  const std::string port = std::to_string(closed_port());
  const auto out = tmp_dir() / "refused.h5";
  const auto r = run_cli("measure --instrument tcp://127.0.0.1:" + port + " --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.err;  // a dead instrument is bad input (docs/cli.md), not an internal failure
  EXPECT_NE(r.err.find("the instrument at tcp://127.0.0.1:" + port + " refused the connection"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("switched on"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("address and port"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("piezobench sim-instrument --port " + port), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  // The same in --json: an error object of kind "instrument".
  const auto j = run_cli("measure --instrument tcp://127.0.0.1:" + port + " --json --out " + out.string());
  EXPECT_EQ(j.exit_code, 2);
  const auto e = nlohmann::json::parse(j.out)["error"];
  EXPECT_EQ(e["kind"], "instrument");
  EXPECT_NE(e["message"].get<std::string>().find("refused the connection"), std::string::npos) << j.out;
}

TEST(CliErrors, APortInUseNamesAnotherPort) {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);  // holds a loopback port while sim-instrument tries it
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(::listen(fd, 1), 0);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  const std::string port = std::to_string(ntohs(a.sin_port));
  const auto r = run_cli("sim-instrument --host 127.0.0.1 --port " + port + " --seconds 1");
  ::close(fd);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("cannot listen on 127.0.0.1:" + port), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("choose another --port"), std::string::npos) << r.err;
}

TEST(CliErrors, AnExistingOutIsNeverOverwrittenWithoutOverwrite) {
  TmpCleanup cleanup;
  const auto out = tmp_dir() / "s.h5";
  std::ofstream(out) << "an earlier capture";
  const std::string args = "measure --instrument sim --samples 2000 --shots 1 --out " + out.string();
  const auto r = run_cli(args);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(out.string() + " already exists"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--overwrite"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(out), "an earlier capture");  // untouched
  const auto w = run_cli(args + " --overwrite --json");
  ASSERT_EQ(w.exit_code, 0) << w.err;
  EXPECT_EQ(nlohmann::json::parse(w.out)["shots_written"], 1);
  EXPECT_NE(slurp(out), "an earlier capture");
}

TEST(CliErrors, AnImpedanceFileGivenAsACapturePointsToFigures) {
  const std::string file = kFixtures + "eqcirc3/RB5100.txt";
  for (const std::string cmd : {"impedance ", "capture info "}) {
    const auto r = run_cli(cmd + file);
    EXPECT_EQ(r.exit_code, 2) << cmd << r.err;
    EXPECT_NE(r.err.find(file + " is an impedance analyzer's file (HP 4294A"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("piezobench figures " + file), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("not a readable HDF5"), std::string::npos) << r.err;
  }
  // A file that is neither keeps the capture reader's own message.
  TmpCleanup cleanup;
  const auto junk = tmp_dir() / "junk.h5";
  std::ofstream(junk) << "neither a capture nor an impedance table\n";
  const auto r = run_cli("impedance " + junk.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("not a readable HDF5 file"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("figures"), std::string::npos) << r.err;
}

TEST(CliErrors, NoInternalFunctionNamesInMessages) {
  const auto m = run_cli("model modal --material unobtainium");
  EXPECT_EQ(m.exit_code, 2) << m.err;
  EXPECT_NE(m.err.find("unknown material 'unobtainium'"), std::string::npos) << m.err;
  EXPECT_EQ(m.err.find("find_preset"), std::string::npos) << m.err;
  TmpCleanup cleanup;
  const auto d = run_cli("measure --instrument sim --disturbance wobble=3 --out " + (tmp_dir() / "d.h5").string());
  EXPECT_EQ(d.exit_code, 2) << d.err;
  EXPECT_NE(d.err.find("wobble"), std::string::npos) << d.err;
  EXPECT_EQ(d.err.find("parse_disturbances"), std::string::npos) << d.err;
  const auto f = run_cli("figures /nonexistent/z.txt");
  EXPECT_EQ(f.exit_code, 2) << f.err;
  EXPECT_EQ(f.err.find("read_impedance_"), std::string::npos) << f.err;
}

TEST(CliErrors, DidYouMeanForAMistypedCommandOrOption) {
  const auto c = run_cli("replya a.h5 --out r.h5");
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_NE(c.err.find("'replya' is not a command: did you mean 'replay'?"), std::string::npos) << c.err;
  const auto o = run_cli("replay a.h5 --out r.h5 --job 2");
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("--job: did you mean '--jobs'?"), std::string::npos) << o.err;
  const auto n = run_cli("model modl");
  EXPECT_NE(n.err.find("did you mean 'modal'?"), std::string::npos) << n.err;
  const auto s = run_cli("impedance x.h5 --methd fft");
  EXPECT_NE(s.err.find("--methd: did you mean '--method'?"), std::string::npos) << s.err;
  // Nothing near: no guess.
  const auto far = run_cli("frobnicate");
  EXPECT_EQ(far.exit_code, 2);
  EXPECT_EQ(far.err.find("did you mean"), std::string::npos) << far.err;
}

TEST(CliErrors, ReplayJobsDefaultsToTheCores) {
  const auto h = run_cli("replay --help");
  ASSERT_EQ(h.exit_code, 0) << h.err;
  const std::size_t cores = std::clamp<std::size_t>(std::thread::hardware_concurrency(), 1, 256);
  std::istringstream lines(h.out);
  std::string line, jobs_line;
  while (std::getline(lines, line))
    if (line.find("--jobs") != std::string::npos) jobs_line = line;
  EXPECT_NE(jobs_line.find("--jobs UINT=" + std::to_string(cores) + " "), std::string::npos) << h.out;  // CLI11's default
  EXPECT_NE(h.out.find("default: the number of cores"), std::string::npos) << h.out;
}

TEST(Suggest, NearestNames) {
  using piezo::cli::edit_distance;
  using piezo::cli::nearest_names;
  EXPECT_EQ(edit_distance("replya", "replay"), 1u);  // a transposition
  EXPECT_EQ(edit_distance("", "abc"), 3u);
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
  const std::vector<std::string> cmds = {"demo", "measure", "replay", "replay-merge", "figures", "model"};
  EXPECT_EQ(nearest_names("replya", cmds), std::vector<std::string>{"replay"});
  EXPECT_EQ(nearest_names("mesure", cmds), std::vector<std::string>{"measure"});
  EXPECT_EQ(nearest_names("figure", cmds), std::vector<std::string>{"figures"});
  EXPECT_TRUE(nearest_names("xyz", cmds).empty());
  EXPECT_TRUE(nearest_names("mo", cmds).empty());  // too short to guess
  const std::vector<std::string> opts = {"--jobs", "--json", "--out", "--overwrite", "--material", "--method"};
  EXPECT_EQ(nearest_names("--job", opts), std::vector<std::string>{"--jobs"});
  EXPECT_EQ(nearest_names("--materail", opts), std::vector<std::string>{"--material"});
  EXPECT_EQ(nearest_names("--overw", opts), std::vector<std::string>{"--overwrite"});  // a unique prefix
  // Two at the same distance: both.
  EXPECT_EQ(nearest_names("--abx", {"--abc", "--abd", "--xyz"}), (std::vector<std::string>{"--abc", "--abd"}));
}
