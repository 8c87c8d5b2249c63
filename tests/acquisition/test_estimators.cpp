// The impedance estimator registry (acquisition/estimators/): its checks, the
// builtin list, dispatch by key reaching the estimator of that key, and the
// docs' table equal to the registry's.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <vector>

#include "acquisition/estimators/estimator.hpp"
#include "tests/support/doc_table.hpp"

using namespace piezo;
using namespace piezo::acq;

namespace {

EstimatorEntry trivial(const std::string& key) {
  EstimatorEntry e;
  e.key = key;
  e.label = "trivial";
  e.caps.transient_shots = true;
  e.estimate = [](const EstimateInput&) { return dsp::ImpedanceResult{}; };
  return e;
}

// A two-mode-free RC divider response to a decaying drive: v2 across C behind R1.
// Seeded-free and exact enough for "which estimator ran" (not for accuracy).
struct RcRecord {
  std::vector<double> v1, v2;
  dsp::DividerRecord view() const { return {v1, v2, 1e6, 1000.0, 0, std::nullopt}; }
};

RcRecord rc_record(double amplitude) {
  RcRecord r;
  const double fs = 1e6, tau_rc = 1000.0 * 100e-9, decay = 3000.0;
  double v2 = 0.0;
  for (int k = 0; k < 4000; ++k) {
    const double t = k / fs;
    const double v1 = amplitude * std::exp(-decay * t) * std::sin(2 * M_PI * 5e3 * t);
    v2 += (v1 - v2) * (1.0 / fs) / tau_rc;
    r.v1.push_back(v1);
    r.v2.push_back(v2);
  }
  return r;
}

}  // namespace

TEST(EstimatorRegistry, RejectsDuplicateEmptyAndIncompleteEntries) {
  EstimatorRegistry r;
  r.add(trivial("a"));
  EXPECT_THROW(r.add(trivial("a")), std::invalid_argument);
  EXPECT_THROW(r.add(trivial("")), std::invalid_argument);
  auto no_fn = trivial("b");
  no_fn.estimate = nullptr;
  EXPECT_THROW(r.add(no_fn), std::invalid_argument);
  auto no_label = trivial("c");
  no_label.label.clear();
  EXPECT_THROW(r.add(no_label), std::invalid_argument);
  auto needs_nothing = trivial("d");
  needs_nothing.caps.transient_shots = false;
  EXPECT_THROW(r.add(needs_nothing), std::invalid_argument);
  EXPECT_EQ(r.keys(), std::vector<std::string>{"a"});
  EXPECT_EQ(r.find("zzz"), nullptr);
  EXPECT_THROW(r.at("zzz"), std::invalid_argument);
}

TEST(EstimatorRegistry, BuiltinListsTheFourEstimatorsWithTheirCapabilities) {
  const auto& r = builtin_estimators();
  EXPECT_EQ(r.keys(), (std::vector<std::string>{"prony", "fft", "xspec", "sine"}));
  EXPECT_EQ(r.keys([](const EstimatorEntry& e) { return e.caps.transient_shots; }),
            (std::vector<std::string>{"prony", "fft", "xspec"}));
  EXPECT_TRUE(r.at("prony").caps.modes);
  EXPECT_TRUE(r.at("prony").caps.averages_shots);
  EXPECT_TRUE(r.at("xspec").caps.segments);
  EXPECT_FALSE(r.at("xspec").caps.averages_shots);
  EXPECT_TRUE(r.at("sine").caps.sine_shots);
  for (const auto& e : r.entries()) {
    EXPECT_FALSE(e.description.empty()) << e.key;
    EXPECT_EQ(e.caps.sigma_per_point, !e.sigma_source.empty()) << e.key;
  }
  EXPECT_EQ(join_keys(r.keys()), "prony, fft, xspec or sine");
}

// Each key reaches its own estimator: the result's method names it.
TEST(EstimatorRegistry, DispatchByKeyReachesThatEstimator) {
  const RcRecord a = rc_record(1.0), b = rc_record(1.0);
  const std::vector<dsp::DividerRecord> recs{a.view(), b.view()};
  AssessmentOptions opt;
  opt.prony.bootstrap = 0;
  opt.xspec.segment = 2000;
  const EstimateBand band{200.0, 20e3, 200.0};
  for (const std::string key : {"prony", "fft", "xspec"}) {
    const auto r = builtin_estimators().at(key).estimate(EstimateInput{recs, {}, band, opt, std::nullopt, 0});
    EXPECT_EQ(r.method.substr(0, key.size()), key);
    EXPECT_GT(r.f_hz.size(), 0) << key;
  }
  // Stepped sine: one record per frequency.
  std::vector<RcRecord> sines;
  std::vector<double> freqs{2e3, 5e3, 8e3};
  for (double f : freqs) {
    RcRecord s;
    double v2 = 0.0;
    for (int k = 0; k < 4000; ++k) {
      const double v1 = std::sin(2 * M_PI * f * k / 1e6);
      v2 += (v1 - v2) * 1e-6 / (1000.0 * 100e-9);
      s.v1.push_back(v1);
      s.v2.push_back(v2);
    }
    sines.push_back(std::move(s));
  }
  std::vector<dsp::DividerRecord> sv;
  for (const auto& s : sines) sv.push_back(s.view());
  const auto& sine = builtin_estimators().at("sine");
  const auto r = sine.estimate(EstimateInput{sv, freqs, {0.0, 0.0, 0.0}, opt, std::nullopt, std::nullopt});
  EXPECT_EQ(r.method, "sine");
  EXPECT_EQ(r.f_hz.size(), 3);
  EXPECT_THROW(sine.estimate(EstimateInput{sv, {}, {}, opt, std::nullopt, std::nullopt}), std::invalid_argument);
}

TEST(EstimatorRegistry, MeanRecordAveragesSampleBySample) {
  const RcRecord a = rc_record(1.0), b = rc_record(3.0);
  const std::vector<dsp::DividerRecord> recs{a.view(), b.view()};
  const OwnedRecord m = mean_record(recs);
  ASSERT_EQ(m.v1.size(), a.v1.size());
  for (std::size_t i = 0; i < m.v1.size(); i += 97) EXPECT_DOUBLE_EQ(m.v1[i], (a.v1[i] + b.v1[i]) / 2) << i;
  EXPECT_EQ(m.r1_ohm, 1000.0);
  EXPECT_THROW(mean_record({}), std::invalid_argument);
}

// acquisition/README.md's table of the estimators is the registry's.
TEST(EstimatorRegistry, DocsTableIsTheRegistrys) {
  const std::string table = estimator_table_markdown();
  EXPECT_EQ(test::doc_table("acquisition/README.md", table.substr(0, table.find('\n'))), table)
      << "update acquisition/README.md's estimator table to:\n" << table;
}

// The synopses of README.md and docs/cli.md spell --method's choices as the registry has them.
TEST(EstimatorRegistry, DocsSynopsesListTheRegistrysKeys) {
  const auto& r = builtin_estimators();
  const std::string impedance = "--method " + join_keys(r.keys(), "|", "|");
  const std::string figures =
      "--method oe|" + join_keys(r.keys([](const EstimatorEntry& e) { return e.caps.transient_shots; }), "|", "|");
  for (const std::string page : {"README.md", "docs/cli.md"}) {
    std::ifstream in(std::string(PIEZO_SOURCE_DIR) + "/" + page);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_FALSE(text.empty()) << page;
    EXPECT_NE(text.find(impedance), std::string::npos) << page << " should say " << impedance;
    if (page == "docs/cli.md") {
      EXPECT_NE(text.find(figures), std::string::npos) << page << " should say " << figures;
    }
  }
}
