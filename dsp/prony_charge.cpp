#include "dsp/prony_charge.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "dsp/prony_impedance.hpp"  // summarize(PronyFit)

namespace piezo::dsp {

std::complex<double> ExponentialDrive::laplace(std::complex<double> s) const {
  return amplitude_v / (s - pole_per_s);  // eq. 113
}

std::complex<double> PronyCharge::voltage(std::complex<double> s) const {
  if (drive) return drive->laplace(s);
  if (drive_fit) return laplace(*drive_fit, 0, s);  // eq. 114 applied to v
  throw std::logic_error("PronyCharge: no drive");
}

std::complex<double> PronyCharge::charge(std::complex<double> s) const {
  return laplace(fit, 0, s);
}

std::complex<double> PronyCharge::current(std::complex<double> s) const {
  return s * charge(s);  // eq. 115, q(0−) = 0 (see the header)
}

std::complex<double> PronyCharge::z(double f_hz) const {
  const std::complex<double> s(0.0, 2.0 * std::numbers::pi * f_hz);
  return voltage(s) / current(s);  // eq. 116
}

PronyCharge fit_prony_charge(const Eigen::Ref<const Eigen::VectorXd>& q, double sample_rate_hz,
                             const ExponentialDrive& drive, const PronyOptions& opt) {
  if (!std::isfinite(drive.amplitude_v) || !std::isfinite(drive.pole_per_s) ||
      drive.amplitude_v == 0.0)
    throw std::invalid_argument("fit_prony_charge: the drive needs a finite, non-zero amplitude and a finite pole");
  PronyCharge m;
  m.fit = prony_ss(q, sample_rate_hz, opt);
  m.drive = drive;
  return m;
}

PronyCharge fit_prony_charge(const Eigen::Ref<const Eigen::VectorXd>& q,
                             const Eigen::Ref<const Eigen::VectorXd>& v, double sample_rate_hz,
                             const PronyOptions& opt, const PronyOptions& drive_opt) {
  if (v.size() != q.size())
    throw std::invalid_argument("fit_prony_charge: the drive and the charge need the same samples");
  PronyCharge m;
  m.fit = prony_ss(q, sample_rate_hz, opt);
  m.drive_fit = prony_ss(v, sample_rate_hz, drive_opt);
  return m;
}

ImpedanceResult impedance_from_charge(const PronyCharge& m, const Eigen::VectorXd& f_hz,
                                      const FeatureOptions& features, double feature_step_hz) {
  if (f_hz.size() < 2)
    throw std::invalid_argument("impedance_from_charge: need at least 2 frequencies");
  ImpedanceResult r;
  r.method = "prony-charge";
  r.samples_used = static_cast<std::size_t>(m.fit.samples);
  r.f_hz = f_hz;
  r.z_ohm.resize(f_hz.size());
  for (Eigen::Index k = 0; k < f_hz.size(); ++k) r.z_ohm[k] = m.z(f_hz[k]);
  r.prony = summarize(m.fit);
  const double fmin = std::max(f_hz.minCoeff(), features.fmin_hz);
  const double fmax = std::min(f_hz.maxCoeff(), features.fmax_hz);
  const double step = feature_step_hz > 0
                          ? feature_step_hz
                          : (f_hz.maxCoeff() - f_hz.minCoeff()) / double(f_hz.size() - 1) / 4.0;
  r.features = find_features([&m](double f) { return m.z(f); }, fmin, fmax, step, features);
  return r;
}

}  // namespace piezo::dsp
