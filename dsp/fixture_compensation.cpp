#include "dsp/fixture_compensation.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace piezo::dsp {

namespace {
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
}  // namespace

std::string_view to_string(FixtureModel m) {
  switch (m) {
    case FixtureModel::None:
      return "none";
    case FixtureModel::Open:
      return "open";
    case FixtureModel::Short:
      return "short";
    case FixtureModel::OpenShort:
      return "open-short";
    case FixtureModel::OpenShortLoad:
      return "open-short-load";
  }
  return "none";
}

std::optional<FixtureModel> parse_fixture_model(std::string_view s) {
  for (auto m : {FixtureModel::None, FixtureModel::Open, FixtureModel::Short,
                 FixtureModel::OpenShort, FixtureModel::OpenShortLoad})
    if (s == to_string(m)) return m;
  if (s == "osl") return FixtureModel::OpenShortLoad;
  return std::nullopt;
}

std::string describe(FixtureModel m) {
  switch (m) {
    case FixtureModel::None:
      return "no fixture compensation: Z includes the fixture (lead resistance, fixture "
             "capacitance, DAQ input), "
             "R1 error, channel gain and skew";
    case FixtureModel::Open:
      return "open compensation: the fixture is a shunt admittance across the terminals (fixture "
             "capacitance, DAQ "
             "input), measured open and removed; lead resistance, R1 error and channel gain remain";
    case FixtureModel::Short:
      return "short compensation: the fixture is a series impedance (lead resistance), measured "
             "shorted and "
             "subtracted; fixture capacitance, R1 error and channel gain remain";
    case FixtureModel::OpenShort:
      return "open-short compensation: shunt admittance at the v2 node (fixture capacitance, DAQ "
             "input) followed by "
             "a series lead impedance to the terminals; R1 error and channel gain remain";
    case FixtureModel::OpenShortLoad:
      return "open-short-load compensation: the fixture, R1, channel gain and skew as one general "
             "bilinear error "
             "box per frequency, fixed by the three standards (exact for any linear fixture)";
  }
  return {};
}

cd LoadStandard::impedance(double f) const { return ohm / cd(1.0, kTwoPi * f * ohm * parallel_f); }

FixtureModel FixtureCompensation::best_model(bool open, bool shrt, bool load) {
  if (open && shrt && load) return FixtureModel::OpenShortLoad;
  if (open && shrt) return FixtureModel::OpenShort;
  if (open) return FixtureModel::Open;
  if (shrt) return FixtureModel::Short;
  return FixtureModel::None;
}

FixtureCompensation::FixtureCompensation(FixtureModel model, std::optional<StandardModel> open,
                                         std::optional<StandardModel> shrt,
                                         std::optional<StandardModel> load, LoadStandard load_value)
    : model_(model),
      open_(std::move(open)),
      short_(std::move(shrt)),
      load_(std::move(load)),
      load_value_(load_value) {
  const std::string who = "fixture compensation '" + std::string(to_string(model)) + "'";
  const bool need_open = model == FixtureModel::Open || model == FixtureModel::OpenShort ||
                         model == FixtureModel::OpenShortLoad;
  const bool need_short = model == FixtureModel::Short || model == FixtureModel::OpenShort ||
                          model == FixtureModel::OpenShortLoad;
  if (need_open && !open_)
    throw std::invalid_argument(who + " needs an open standard (shots with role \"open\")");
  if (need_short && !short_)
    throw std::invalid_argument(who + " needs a short standard (shots with role \"short\")");
  if (model == FixtureModel::OpenShortLoad) {
    if (!load_)
      throw std::invalid_argument(who + " needs a load standard (shots with role \"load\")");
    if (!(load_value_.ohm > 0 && std::isfinite(load_value_.ohm) && load_value_.parallel_f >= 0))
      throw std::invalid_argument(who + ": the load standard's value must be R > 0, C >= 0");
  }
}

cd FixtureCompensation::correct_with(double f, cd zm, cd zo, cd zs, cd zl) const {
  switch (model_) {
    case FixtureModel::None:
      return zm;
    case FixtureModel::Open:
      return 1.0 / (1.0 / zm - 1.0 / zo);
    case FixtureModel::Short:
      return zm - zs;
    case FixtureModel::OpenShort: {
      const cd yo = 1.0 / zo,
               zlead = zs / (1.0 - zs * yo);  // = 1/(1/Z_s − Y_o), finite for Z_s = 0
      return 1.0 / (1.0 / zm - yo) - zlead;
    }
    case FixtureModel::OpenShortLoad:
      return load_value_.impedance(f) * (zm - zs) * (zo - zl) / ((zo - zm) * (zl - zs));
  }
  return zm;
}

cd FixtureCompensation::correct(double f, cd zm) const {
  const cd zo = open_ ? open_->impedance(f) : cd(0.0), zs = short_ ? short_->impedance(f) : cd(0.0),
           zl = load_ ? load_->impedance(f) : cd(0.0);
  return correct_with(f, zm, zo, zs, zl);
}

double FixtureCompensation::corrected_sigma(double f, cd zm, double sigma_m) const {
  if (model_ == FixtureModel::None) return sigma_m;
  cd z[4] = {zm, open_ ? open_->impedance(f) : cd(0.0), short_ ? short_->impedance(f) : cd(0.0),
             load_ ? load_->impedance(f) : cd(0.0)};
  const double s[4] = {sigma_m, open_ ? open_->impedance_sigma(f) : 0.0,
                       short_ ? short_->impedance_sigma(f) : 0.0,
                       load_ ? load_->impedance_sigma(f) : 0.0};
  // The correction is analytic in each argument: |∂Z_x/∂Z_i| by a complex central difference.
  double var = 0;
  for (int i = 0; i < 4; ++i) {
    if (!(s[i] > 0)) continue;
    const double h = 1e-6 * std::max(std::abs(z[i]), 1e-12);
    cd zp[4] = {z[0], z[1], z[2], z[3]}, zn[4] = {z[0], z[1], z[2], z[3]};
    zp[i] += h;
    zn[i] -= h;
    const cd d = (correct_with(f, zp[0], zp[1], zp[2], zp[3]) -
                  correct_with(f, zn[0], zn[1], zn[2], zn[3])) /
                 (2 * h);
    var += std::norm(d) * s[i] * s[i];
  }
  return std::sqrt(var);
}

void FixtureCompensation::apply(ImpedanceResult& r) const {
  if (model_ == FixtureModel::None) return;
  const bool sig = r.z_sigma_ohm.size() == r.f_hz.size();
  Eigen::VectorXd sigma(r.f_hz.size());
  for (Eigen::Index k = 0; k < r.f_hz.size(); ++k) {
    sigma[k] = corrected_sigma(r.f_hz[k], r.z_ohm[k], sig ? r.z_sigma_ohm[k] : 0.0);
    r.z_ohm[k] = correct(r.f_hz[k], r.z_ohm[k]);
  }
  r.z_sigma_ohm = sigma;  // the standards' part even when the estimate had no σ
}

}  // namespace piezo::dsp
