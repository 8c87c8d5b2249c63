#include "model/harmonic.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace piezo::model {

namespace {
void check_freqs(std::span<const double> f, const char* fn) {
  for (double x : f)
    if (!(x >= 0) || !std::isfinite(x))
      throw std::invalid_argument(std::string(fn) + ": frequencies must be finite and >= 0");
}
}  // namespace

std::vector<Complex> admittance_modal(const ModalPortModel& port, std::span<const double> freq_hz,
                                      const RayleighDamping& damping,
                                      const MaterialLosses& losses) {
  check_freqs(freq_hz, "admittance_modal");
  damping.validate();
  losses.validate();
  std::vector<Complex> y(freq_hz.size());
  for (std::size_t i = 0; i < freq_hz.size(); ++i) {
    const double w = 2.0 * M_PI * freq_hz[i];
    y[i] = Complex(0.0, w) * port.charge_per_volt(w, damping, losses);
  }
  return y;
}

std::vector<Complex> impedance_from_admittance(std::span<const Complex> y) {
  std::vector<Complex> z(y.size());
  for (std::size_t i = 0; i < y.size(); ++i)
    z[i] = y[i] == Complex(0.0) ? Complex(std::numeric_limits<double>::infinity(), 0.0)
                                : 1.0 / y[i];
  return z;
}

std::vector<double> frequency_grid(double fmin_hz, double fmax_hz, double step_hz) {
  if (!(fmin_hz >= 0) || !(fmax_hz >= fmin_hz) || !(step_hz > 0) || !std::isfinite(fmax_hz))
    throw std::invalid_argument("frequency_grid: need 0 <= fmin <= fmax and step > 0");
  const double n = std::floor((fmax_hz - fmin_hz) / step_hz + 1e-9);
  if (n > 1e7) throw std::invalid_argument("frequency_grid: more than 1e7 points");
  std::vector<double> f;
  f.reserve(static_cast<std::size_t>(n) + 1);
  for (long i = 0; i <= static_cast<long>(n); ++i) f.push_back(fmin_hz + i * step_hz);
  return f;
}

DirectHarmonicSolver::DirectHarmonicSolver(const TubeModel& model) : model_(&model) {
  const auto& sys = model.system();
  const SpMat& p = sys.pattern();
  const int v = model.dofs().electrode();
  for (int q = p.outerIndexPtr()[v]; q < p.outerIndexPtr()[v + 1]; ++q) {
    const int i = p.innerIndexPtr()[q];
    col_v_.push_back(q);
    row_v_.push_back(sys.position(v, i));
  }
  diag_v_ = sys.position(v, v);
}

std::vector<Complex> DirectHarmonicSolver::admittance(const PiezoMaterialE& material,
                                                      std::span<const double> freq_hz,
                                                      const RayleighDamping& damping,
                                                      const MaterialLosses& losses,
                                                      double end_mass_fraction) {
  validate(material, "DirectHarmonicSolver::admittance");
  check_freqs(freq_hz, "DirectHarmonicSolver::admittance");
  damping.validate();
  losses.validate();
  if (!std::isfinite(end_mass_fraction) || end_mass_fraction < 0)
    throw std::invalid_argument(
        "DirectHarmonicSolver::admittance: end_mass_fraction must be finite and >= 0");
  const auto w = weights(material);
  const double eta = std::isfinite(losses.qm) ? 1.0 / losses.qm : 0.0;
  const int v = model_->dofs().electrode();
  const int n = model_->dofs().n_total();
  std::vector<Complex> y(freq_hz.size());
  Eigen::VectorXcd rhs(n), x(n), col(n);
  for (std::size_t k = 0; k < freq_hz.size(); ++k) {
    const double om = 2.0 * M_PI * freq_hz[k];
    if (om == 0.0) {
      y[k] = 0.0;
      continue;
    }
    std::array<Complex, kNumMaterialParams> cw;
    for (int i = 0; i < 5; ++i) cw[i] = w[i] * Complex(1.0, eta + om * damping.beta);
    for (int i = 5; i < 8; ++i) cw[i] = w[i];
    for (int i = 8; i < 10; ++i) cw[i] = w[i] * Complex(1.0, -losses.tan_delta);
    model_->system().combine(cw, Complex(-om * om, om * damping.alpha), a_, end_mass_fraction);
    // Lift V = 1: rhs = −A(:, V); then decouple the V row/column.
    col.setZero();
    Complex* val = a_.valuePtr();
    for (int q : col_v_) col[a_.innerIndexPtr()[q]] = val[q];
    rhs = -col;
    rhs[v] = 1.0;
    for (std::size_t j = 0; j < col_v_.size(); ++j) {
      val[col_v_[j]] = 0.0;
      val[row_v_[j]] = 0.0;
    }
    val[diag_v_] = 1.0;
    if (!analysed_) {
      lu_.analyzePattern(a_);
      analysed_ = true;
    }
    lu_.factorize(a_);
    if (lu_.info() != Eigen::Success) {
      y[k] = Complex(std::numeric_limits<double>::quiet_NaN(), 0.0);  // status: singular
      continue;
    }
    x = lu_.solve(rhs);
    const Complex q = -col.transpose() * x;  // Q = −(A x)_V, A symmetric (not Hermitian)
    y[k] = Complex(0.0, om) * q;
  }
  return y;
}

}  // namespace piezo::model
