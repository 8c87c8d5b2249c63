#include "bvd_model.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

namespace piezo::bvd {

using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

cd Bvd::admittance(cd s) const {
  cd y = s * c0;
  for (const auto& b : branches) y += 1.0 / (b.R + s * b.L + 1.0 / (s * b.C));
  return y;
}

std::complex<double> Bvd::impedance_at(double f_hz) const {
  return 1.0 / admittance(cd(0.0, kTwoPi * f_hz));
}

double Bvd::static_capacitance() const {
  double c = c0;
  for (const auto& b : branches) c += b.C;
  return c;
}

Bvd make_bvd(const std::vector<double>& fr, const std::vector<double>& fa, double c0,
             const std::vector<double>& zeta) {
  const auto n = fr.size();
  if (fa.size() != n || zeta.size() != n) throw std::invalid_argument("make_bvd: sizes differ");
  // Lossless Y(jω)/(jω) = C0 + Σ C_n/(1 − ω²/ω_rn²) = 0 at every ω = ω_ak.
  Eigen::MatrixXd m(n, n);
  Eigen::VectorXd rhs = Eigen::VectorXd::Constant(n, -c0);
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t j = 0; j < n; ++j) m(k, j) = 1.0 / (1.0 - std::pow(fa[k] / fr[j], 2));
  Eigen::VectorXd c = m.fullPivLu().solve(rhs);
  Bvd b;
  b.c0 = c0;
  for (std::size_t j = 0; j < n; ++j) {
    if (!(c[j] > 0)) throw std::invalid_argument("make_bvd: fr/fa pattern not realizable");
    const double w = kTwoPi * fr[j];
    Branch br;
    br.C = c[j];
    br.L = 1.0 / (w * w * br.C);
    br.R = 2.0 * zeta[j] * std::sqrt(br.L / br.C);
    b.branches.push_back(br);
  }
  return b;
}

Bvd make_bvd_rayleigh(const std::vector<double>& fr, const std::vector<double>& fa, double c0,
                      double alpha, double beta) {
  std::vector<double> z;
  for (double f : fr) z.push_back(0.5 * (alpha / (kTwoPi * f) + beta * kTwoPi * f));
  return make_bvd(fr, fa, c0, z);
}

namespace {
const std::vector<double> kFr = {50.3e3, 53.4e3, 79.4e3};
const std::vector<double> kFa = {51.1e3, 54.0e3, 95.1e3};
}  // namespace

Bvd tube_bvd_q(double q) { return make_bvd(kFr, kFa, 2.5e-9, std::vector<double>(3, 0.5 / q)); }
Bvd tube_bvd_rayleigh(double beta) { return make_bvd_rayleigh(kFr, kFa, 2.5e-9, 0.0, beta); }

double ExpSum::at(double t) const {
  cd acc = 0;
  for (std::size_t n = 0; n < lambda.size(); ++n) acc += residue[n] * std::exp(lambda[n] * t);
  return acc.real();
}

cd ExpSum::laplace(cd s) const {
  cd acc = 0;
  for (std::size_t n = 0; n < lambda.size(); ++n) acc += residue[n] / (s - lambda[n]);
  return acc;
}

DividerResponse divider_response(const Bvd& bvd, double r1, double amp, double a) {
  // States (time unit T = 1 µs, branch currents scaled by R1 to volts):
  // x = [v2, R1·i_1, vc_1, R1·i_2, vc_2, ...], input u = v1.
  const double T = 1e-6;
  const auto nb = static_cast<Eigen::Index>(bvd.branches.size());
  const Eigen::Index n = 1 + 2 * nb;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  const double g0 = T / (r1 * bvd.c0);
  A(0, 0) = -g0;
  b[0] = g0;
  for (Eigen::Index k = 0; k < nb; ++k) {
    const auto& br = bvd.branches[static_cast<std::size_t>(k)];
    const Eigen::Index ij = 1 + 2 * k, vc = 2 + 2 * k;
    A(0, ij) = -g0;                          // C0 dv2/dt = (u − v2 − Σ R1 i)/R1
    A(ij, 0) = T * r1 / br.L;                // L di/dt = v2 − R i − vc
    A(ij, ij) = -T * br.R / br.L;
    A(ij, vc) = -T * r1 / br.L;
    A(vc, ij) = T / (r1 * br.C);             // C dvc/dt = i
  }
  Eigen::ComplexEigenSolver<Eigen::MatrixXcd> es(A.cast<cd>());
  const Eigen::MatrixXcd W = es.eigenvectors();
  const Eigen::VectorXcd wb = W.partialPivLu().solve(b.cast<cd>());
  DividerResponse out;
  out.v1.lambda = {cd(-a, 0)};
  out.v1.residue = {cd(amp, 0)};
  cd r_input = 0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const cd lam = es.eigenvalues()[k] / T;
    // x(t) = Σ_k w_k (W⁻¹b)_k A ∫0^t e^{λ(t−τ)} e^{−aτ} dτ·(1/T): the 1/T of the
    // time scaling cancels the T of ∫ dτ in µs.
    const cd r = W(0, k) * wb[k] * amp / (lam + a) / T;
    out.v2.lambda.push_back(lam);
    out.v2.residue.push_back(r);
    out.circuit_poles.push_back(lam);
    r_input -= r;
  }
  out.v2.lambda.push_back(cd(-a, 0));
  out.v2.residue.push_back(r_input);
  // i = (v1 − v2)/R1 on the same poles.
  out.i.lambda = out.v2.lambda;
  for (std::size_t k = 0; k < out.v2.residue.size(); ++k)
    out.i.residue.push_back(-out.v2.residue[k] / r1);
  out.i.residue.back() += amp / r1;
  return out;
}

std::vector<double> sample(const ExpSum& x, double fs, std::size_t n, std::size_t pretrigger) {
  std::vector<double> out(n, 0.0);
  for (std::size_t k = pretrigger; k < n; ++k) out[k] = x.at(double(k - pretrigger) / fs);
  return out;
}

double std_dev(const std::vector<double>& x) {
  long double s = 0, s2 = 0;
  for (double v : x) s += v;
  const long double mean = s / x.size();
  for (double v : x) s2 += (v - mean) * (v - mean);
  return static_cast<double>(std::sqrt(s2 / x.size()));
}

std::vector<double> add_noise(const std::vector<double>& x, double fraction, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> nd(0.0, fraction * std_dev(x));
  std::vector<double> out = x;
  for (double& v : out) v += nd(rng);
  return out;
}

}  // namespace piezo::bvd
