#pragma once
// Shared by the replay tests: small simulated captures made with
// `piezobench measure`, and the content of a results file in a form that
// compares independently of record order and of wall-clock fields.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "acquisition/results_file.hpp"
#include "tests/support/run_cli.hpp"

namespace piezo::test {

namespace fs = std::filesystem;

inline fs::path fresh_dir(const std::string& name) {
  auto d = fs::temp_directory_path() / ("piezobench-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// A short simulated capture of an isotropic tube whose Young's modulus is
// `ye11` (the batch's transducers differ a little), seeded noise.
inline void make_capture(const fs::path& file, double ye11, int seed) {
  fs::create_directories(file.parent_path());
  char set[160];
  std::snprintf(set, sizeof set, "YE11=%.6g,nu12=0.3333,d31=-210e-12,epsT33_rel=2294", ye11);
  auto r = run_cli("measure --instrument sim --sim-isotropic --sim-set " + std::string(set) +
                   " --noise 0.005 --seed " + std::to_string(seed) +
                   " --samples 8000 --shots 1 --overwrite --out '" + file.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

// The JSON lines of a --jsonl file.
inline std::vector<nlohmann::json> read_lines(const fs::path& f) {
  std::vector<nlohmann::json> out;
  std::ifstream in(f);
  for (std::string line; std::getline(in, line);) out.push_back(nlohmann::json::parse(line));
  return out;
}

// A capture cut in half: a real file that no HDF5 reader accepts.
inline void make_truncated_capture(const fs::path& file) {
  make_capture(file, 6.66e10, 99);
  fs::resize_file(file, fs::file_size(file) / 2);
}

// What a record says, without what legitimately differs from run to run:
// wall-clock fields (elapsed_s, replayed_utc, stage notes with timings, the
// output-error fit's seconds).
struct Content {
  std::string path, sha256, status;
  nlohmann::json json;
  std::vector<acq::StoredCurve> curves;
};

inline nlohmann::json without_timing(nlohmann::json j) {
  if (j.contains("result") && j["result"].contains("stages"))
    for (auto& s : j["result"]["stages"]) s.erase("note");
  if (j.contains("result") && j["result"].contains("output_error")) j["result"]["output_error"].erase("seconds");
  if (j.contains("result") && j["result"].contains("diagnosis") && j["result"]["diagnosis"].is_object())
    j["result"]["diagnosis"].erase("seconds");
  if (j.contains("result") && j["result"].contains("work"))  // the counts stay, the wall times go
    for (auto& p : j["result"]["work"]["phases"]) p.erase("seconds");
  return j;
}

inline std::map<std::string, Content> read_content(const fs::path& results) {
  std::map<std::string, Content> out;
  acq::for_each_result(results,
                       [&](const acq::ResultRecord& r) {
                         out[r.key] = {r.input_path, r.sha256, r.status,
                                       without_timing(nlohmann::json::parse(r.result_json)),
                                       r.curves};
                       },
                       {true});
  return out;
}

// Same keys, same paths, digests, statuses, JSON and curves, bit for bit: the
// pipeline is deterministic (seeded, no threads inside a capture), so one
// capture replayed in any shard, by any worker, gives the same numbers.
inline void expect_same_content(const std::map<std::string, Content>& a,
                                const std::map<std::string, Content>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [key, x] : a) {
    auto it = b.find(key);
    ASSERT_NE(it, b.end()) << "record " << key << " (" << x.path << ") missing";
    const auto& y = it->second;
    EXPECT_EQ(x.path, y.path);
    EXPECT_EQ(x.sha256, y.sha256);
    EXPECT_EQ(x.status, y.status) << x.path;
    EXPECT_EQ(x.json, y.json) << x.path;
    ASSERT_EQ(x.curves.size(), y.curves.size()) << x.path;
    for (std::size_t c = 0; c < x.curves.size(); ++c) {
      EXPECT_EQ(x.curves[c].label, y.curves[c].label);
      EXPECT_EQ(x.curves[c].f_hz, y.curves[c].f_hz) << x.path << " " << x.curves[c].label;
      EXPECT_EQ(x.curves[c].z_ohm, y.curves[c].z_ohm) << x.path << " " << x.curves[c].label;
    }
  }
}

}  // namespace piezo::test
