// Issue 40's acceptance on another tool's captures (../shared/corpus/refsim-v1):
// `piezobench update CAP.h5 --method cmcm` and `--method lm` (jobs::run_update_capture:
// the impedance command's estimate, its features inside the drive's band and
// the model's mode range, an honest status). The rule, for each method:
//   * `converged` only with every feature used inside the band it reports and
//     measured with a sigma;
//   * then each constant within 3 sigma of the truth (truth.json, read here only);
//   * otherwise a refusal (any other status) with its reason in words;
//   * never `converged` with a constant more than 10 sigma off.
// make test runs three cases (two controls the issue named, one with an
// effect); make validate all twenty. scripts/update-methods-corpus.py prints
// the same table from the command line.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "jobs/update_capture_job.hpp"

namespace {
namespace fs = std::filesystem;
using namespace piezo;
const fs::path kCorpus = fs::path(PIEZO_SOURCE_DIR) / ".." / "shared" / "corpus" / "refsim-v1";

#ifdef PIEZO_UPDATE_METHODS_ALL
const char* const kCases[] = {"01", "02", "03", "04", "05", "06", "07", "08", "09", "10",
                              "11", "12", "13", "14", "15", "16", "17", "18", "19", "20"};
#else
const char* const kCases[] = {"03", "12", "05"};
#endif

class UpdateMethodsCorpus : public ::testing::TestWithParam<const char*> {};

TEST_P(UpdateMethodsCorpus, ConvergedWithinThreeSigmaOrRefusedWithReason) {
  const fs::path dir = kCorpus / GetParam();
  if (!fs::exists(dir / "fit.h5")) GTEST_SKIP() << "corpus not found at " << dir;
  nlohmann::json truth;
  std::ifstream(dir / "truth.json") >> truth;
  const auto& t = truth["material"];
  const double tv[4] = {t["YE11_pa"].get<double>(), t["nu12"].get<double>(), t["d31_c_per_n"].get<double>(),
                        t["epsT33_rel"].get<double>()};
  for (const char* method : {"cmcm", "lm"}) {
    jobs::UpdateCaptureRequest req;
    req.file = (dir / "fit.h5").string();
    req.method = method;
    req.warn = [](const std::string&) {};  // the nominal material as the command line picks it
    const auto r = jobs::run_update_capture(req);
    const auto& m = r.methods[method];
    const std::string status = m.value("status", std::string());
    std::printf("[case %s %-4s] %-16s", GetParam(), method, status.c_str());
    const bool converged = m.value("converged", false);
    EXPECT_EQ(converged, status == "converged");
    if (m.contains("parameters"))
      for (std::size_t k = 0; k < 4; ++k) {
        const auto& p = m["parameters"][k];
        const double sigma = p["sigma"].is_number() ? p["sigma"].get<double>() : NAN;
        const double z = (p["value"].get<double>() - tv[k]) / sigma;
        std::printf(" %s %+7.2f%s", p["name"].get<std::string>().c_str(), z,
                    p["status"].get<std::string>() == "ok" ? " " : "*");
        if (converged) {
          EXPECT_LE(std::abs(z), 3.0) << GetParam() << " " << method << " " << p["name"];
          EXPECT_LE(std::abs(z), 10.0) << GetParam() << " " << method << " " << p["name"];
        }
      }
    std::printf("\n  %s\n", m.value("message", std::string()).c_str());
    if (converged) {
      const auto& f = m["features"];
      const double lo = f["band"]["lo_hz"].get<double>(), hi = f["band"]["hi_hz"].get<double>();
      ASSERT_GT(hi, lo);
      for (const char* k : {"resonances_hz", "antiresonances_hz"})
        for (const auto& x : f[k]) {
          EXPECT_GE(x.get<double>(), lo) << k;
          EXPECT_LE(x.get<double>(), hi) << k;
        }
      for (const char* k : {"resonances_sigma_hz", "antiresonances_sigma_hz"})
        for (const auto& x : f[k]) EXPECT_GT(x.get<double>(), 0.0) << k;
      EXPECT_GT(f["low_z_sigma_ohm"].get<double>(), 0.0);
    } else {
      EXPECT_FALSE(m.value("message", std::string()).empty()) << "a refusal without its reason";
    }
  }
}

#ifdef PIEZO_UPDATE_METHODS_ALL
INSTANTIATE_TEST_SUITE_P(RefsimV1All, UpdateMethodsCorpus, ::testing::ValuesIn(kCases));  // make validate
#else
INSTANTIATE_TEST_SUITE_P(RefsimV1, UpdateMethodsCorpus, ::testing::ValuesIn(kCases));
#endif

}  // namespace
