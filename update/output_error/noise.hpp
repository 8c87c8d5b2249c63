#pragma once
// Noise and baseline of the output-error fit's record: the noise of the
// filtered error (the shots' scatter, else the pretrigger, else each
// channel's high-pass estimate) and the DAQ offsets' whitening.
// Internal to update/output_error/.
#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

#include <memory>

#include "update/output_error/baseline.hpp"
#include "update/output_error/common.hpp"
#include "update/output_error/forward_model.hpp"
#include "update/output_error/shot_average.hpp"

namespace piezo::update::oe {

// The noise of a record's filtered error at transfer t: the shots' scatter,
// else the pretrigger, else each channel's high-pass estimate.
struct RecordNoise {
  double sigma = 0;       // of the filtered, decimated error (the (averaged) record's)
  double ch1 = 0, ch2 = 0;  // white noise of each channel of the (averaged) record, volts
  double dof = 0;         // degrees of freedom of the estimate
  std::string source;
};

RecordNoise record_noise(Problem& prob, const Averaged& rec, const std::vector<cd>& t);

// The DAQ offsets. Removed with the pretrigger's mean, each channel keeps an
// error of σ_raw/√P, constant over the record: in the filtered error a
// component along u = L ∗ 1 (v1's offset reaches v2 through T, which is 1
// at low frequency) of variance τ² = (σ1² + σ2²)/P — correlated noise that
// white weighting would count as lack of fit. It is marginalised: the
// residual is whitened with the covariance σ²I + τ²uuᵀ (its component along
// u shrunk by 1/√(1 + τ²uᵀu/σ²)). Without a pretrigger the offsets are
// unknown (τ = ∞): the component is projected out, one degree of freedom less.
//
// With a slow disturbance found (baseline.hpp: decide_disturbances, then
// use()): the residual is first whitened for 1/f noise (PinkFilter), then the
// baseline's filtered-and-whitened columns (the offset among them) are
// projected out — dof their rank.
struct OffsetWhitening {
  Eigen::VectorXd u;
  double uu = 0;
  double shrink = 1.0;  // 1 − 1/√(1 + τ²uᵀu/σ²): the share of the u component removed
  int dof = 1;
  std::string model;
  std::shared_ptr<const PinkFilter> pink;  // 1/f whitening (none: white noise)
  Eigen::MatrixXd q;                        // orthonormal nuisance columns, projected out (none: u as above)
  Eigen::MatrixXd columns;                  // the baseline's raw filtered columns (volts per coefficient)
  DisturbanceModel disturbances;
  OffsetWhitening(Problem& prob, const Averaged& rec, const std::vector<cd>& t_nominal,
                  double sigma);
  // Switches to the disturbance model d (its columns at transfer t).
  void use(const DisturbanceModel& d, Problem& prob, const Averaged& rec, const std::vector<cd>& t);
  Eigen::VectorXd operator()(Eigen::VectorXd r) const {
    if (pink) r = (*pink)(r);
    if (q.cols() > 0) {
      r -= q * (q.transpose() * r);
      return r;
    }
    if (uu > 0 && shrink > 0) r -= (shrink * u.dot(r) / uu) * u;
    return r;
  }
};

}  // namespace piezo::update::oe
