// The output-error fit's baseline columns (update/output_error/baseline.hpp):
// L ∗ b at the kept samples for each slow basis function b, kept once per
// problem (Problem::kept_column). Checked against the same filter applied
// directly (Problem::deviation of the polynomial and the hum written out
// here): the columns do not depend on the transfer T (a second call with
// another T returns the same, and so does a fork of the problem), a second
// record of the same shape (other samples) gets the same columns, problems
// sharing a record's columns compute them once, and a record filtered with
// another band gets its own.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "dsp/work_counters.hpp"
#include "model/modal.hpp"
#include "tests/support/oe_test_tube.hpp"
#include "update/output_error/baseline.hpp"
#include "update/output_error/forward_model.hpp"
#include "update/output_error/noise.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;

constexpr double kFs = 1e6;        // 40 ms records: three hum harmonics fit
constexpr std::size_t kN = 40000;

update::oe::Averaged record(unsigned seed, double noise = 0.01) { return test::decaying_record(kN, kFs, seed, noise); }

// P0..P3 on [−1, 1] and cos/sin(2π·h·f·t): the basis the columns filter.
std::vector<std::vector<double>> basis(double mains_hz) {
  std::vector<std::vector<double>> out;
  for (int k = 0; k <= 3; ++k) {
    std::vector<double> b(kN);
    for (std::size_t i = 0; i < kN; ++i) {
      const double x = 2.0 * double(i) / double(kN - 1) - 1.0;
      b[i] = k == 0 ? 1.0 : k == 1 ? x : k == 2 ? 0.5 * (3 * x * x - 1) : 0.5 * (5 * x * x * x - 3 * x);
    }
    out.push_back(b);
  }
  for (int h = 1; h <= 3; ++h) {
    std::vector<double> c(kN), s(kN);
    for (std::size_t i = 0; i < kN; ++i) {
      const double ph = 2.0 * std::numbers::pi * h * mains_hz * double(i) / kFs;
      c[i] = std::cos(ph);
      s[i] = std::sin(ph);
    }
    out.push_back(c);
    out.push_back(s);
  }
  return out;
}

// The columns the filter gives, one deviation each (−b on v2, nothing on v1).
Eigen::MatrixXd direct(update::oe::Problem& prob, const std::vector<cd>& t, double mains_hz) {
  const auto b = basis(mains_hz);
  const std::vector<double> zero(kN, 0.0);
  Eigen::MatrixXd cols(static_cast<Eigen::Index>(prob.samples()), static_cast<Eigen::Index>(b.size()));
  for (std::size_t c = 0; c < b.size(); ++c) {
    std::vector<double> neg(kN);
    for (std::size_t i = 0; i < kN; ++i) neg[i] = -b[c][i];
    cols.col(static_cast<Eigen::Index>(c)) = prob.deviation(t, zero, neg);
  }
  return cols;
}

class BaselineColumns : public test::OeTestTube {
 protected:
  update::OeData data() const { return bench_data(kFs); }
  update::oe::Coordinates5 co() const { return nominal_coordinates(); }
};

// The columns against the filter applied directly, to rounding (the
// polynomial is written out here, not taken from baseline.cpp).
void expect_columns(const Eigen::MatrixXd& got, const Eigen::MatrixXd& want) {
  ASSERT_EQ(got.rows(), want.rows());
  ASSERT_EQ(got.cols(), want.cols());
  for (Eigen::Index c = 0; c < want.cols(); ++c) {
    const double scale = want.col(c).cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    EXPECT_LT((got.col(c) - want.col(c)).cwiseAbs().maxCoeff(), 1e-12 * scale) << "column " << c;
  }
}

}  // namespace

TEST_F(BaselineColumns, DoNotDependOnTheTransferNorOnTheSamplesAndFollowTheBand) {
  const auto rec = record(1);
  const auto d = data();
  update::oe::Problem prob(solver, cls, co(), rec, d, 100e3, {});
  const Eigen::VectorXd x0 = Eigen::VectorXd::Zero(update::oe::kParams);
  const auto t1 = prob.transfer(x0);
  ASSERT_TRUE(t1.has_value());
  std::vector<cd> t2 = *t1;  // another transfer: the columns must not see it
  for (auto& v : t2) v *= cd(0.7, 0.2);
  const int h = update::oe::hum_harmonics(50.0, double(kN) / kFs);
  ASSERT_EQ(h, 3);

  const Eigen::MatrixXd first = update::oe::baseline_columns(prob, rec, *t1, 3, 50.0, h);
  expect_columns(first, direct(prob, *t1, 50.0));
  const long ffts = dsp::ffts();  // (the kept columns: no transform again)
  const Eigen::MatrixXd again = update::oe::baseline_columns(prob, rec, t2, 3, 50.0, h);
  EXPECT_EQ(again, first);
  EXPECT_EQ(update::oe::baseline_columns(prob, rec, t2, 0, 0.0, 0), first.leftCols(1));

  // A fork of the problem (another thread's) shares what it kept.
  model::ModalSolver other_solver{tube};
  update::oe::Problem fork(prob, other_solver);
  EXPECT_EQ(update::oe::baseline_columns(fork, rec, t2, 3, 50.0, h), first);
  EXPECT_EQ(dsp::ffts(), ffts);

  // Another record of the same shape (other samples): the same columns.
  const auto rec2 = record(2);
  update::oe::Problem prob2(solver, cls, co(), rec2, d, 100e3, {});
  EXPECT_EQ(update::oe::baseline_columns(prob2, rec2, t2, 3, 50.0, h), first);

  // Problems that share one record's columns (the held-out predictions of a
  // diagnosis): the second computes none; one under another band keeps its own.
  const auto share = update::make_record_share();
  update::oe::Problem a(solver, cls, co(), rec, d, 100e3, {});
  a.share_columns(share);
  EXPECT_EQ(update::oe::baseline_columns(a, rec, t2, 3, 50.0, h), first);
  update::oe::Problem b(solver, cls, co(), rec2, d, 100e3, {});
  b.share_columns(share);
  const long before_b = dsp::ffts();
  EXPECT_EQ(update::oe::baseline_columns(b, rec2, t2, 3, 50.0, h), first);
  EXPECT_EQ(dsp::ffts(), before_b);

  // The same record under another low-pass of the same decimation (5): its
  // own columns (also when offered the share).
  update::oe::Problem prob3(solver, cls, co(), rec, d, 90e3, {});
  prob3.share_columns(share);
  const auto t3 = prob3.transfer(x0);
  ASSERT_TRUE(t3.has_value());
  const Eigen::MatrixXd other = update::oe::baseline_columns(prob3, rec, *t3, 3, 50.0, h);
  expect_columns(other, direct(prob3, *t3, 50.0));
  ASSERT_EQ(other.rows(), first.rows());
  EXPECT_GT((other - first).cwiseAbs().maxCoeff(), 1e-3 * first.cwiseAbs().maxCoeff());
}

// The record's white-noise estimates are kept with its columns (record_noise
// asks again at the fit's answer and in each held-out prediction) but, unlike
// the columns, they are of the samples: problems sharing columns with another
// record of the same shape get their own.
TEST_F(BaselineColumns, TheKeptWhiteNoiseIsTheRecordsOwn) {
  const auto quiet = record(3, 0.01), loud = record(4, 0.03);
  const auto d = data();
  const auto share = update::make_record_share();
  update::oe::Problem a(solver, cls, co(), quiet, d, 100e3, {});
  a.share_columns(share);
  update::oe::Problem b(solver, cls, co(), loud, d, 100e3, {});
  b.share_columns(share);
  const auto t = a.transfer(Eigen::VectorXd::Zero(update::oe::kParams));
  ASSERT_TRUE(t.has_value());
  const auto na = update::oe::record_noise(a, quiet, *t);
  const auto nb = update::oe::record_noise(b, loud, *t);
  // The high-pass estimate of white noise, against the truth (v2 = v1/2 + its
  // own noise: √1.25 times v1's) within 10 % (the median of 40 000 sixth
  // differences: ~1 % standard error).
  EXPECT_NEAR(na.ch1, 0.01, 0.001);
  EXPECT_NEAR(na.ch2, 0.01 * std::sqrt(1.25), 0.001);
  EXPECT_NEAR(nb.ch1, 0.03, 0.003);
  EXPECT_NEAR(nb.ch2, 0.03 * std::sqrt(1.25), 0.003);
  // Asked again (the answer's T, another problem on the same record): the same.
  const auto again = update::oe::record_noise(a, quiet, *t);
  EXPECT_EQ(again.ch1, na.ch1);
  EXPECT_EQ(again.ch2, na.ch2);
  update::oe::Problem c(solver, cls, co(), quiet, d, 100e3, {});
  c.share_columns(share);
  EXPECT_EQ(update::oe::record_noise(c, quiet, *t).ch2, na.ch2);
}
