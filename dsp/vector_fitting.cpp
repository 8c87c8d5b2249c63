#include "dsp/vector_fitting.hpp"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace piezo::dsp {

namespace {
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Poles in normalised units s' = s/ω_s: a real pole, or a pair a, a* (Im a > 0).
struct PoleSet {
  std::vector<double> real;
  std::vector<cd> pairs;
  int count() const { return static_cast<int>(real.size() + 2 * pairs.size()); }
  int columns() const { return static_cast<int>(real.size() + 2 * pairs.size()); }
};

// Real basis functions at s: real pole 1/(s − a); pair: 1/(s−a) + 1/(s−a*), j/(s−a) − j/(s−a*).
void basis_row(const PoleSet& p, cd s, std::vector<cd>& out) {
  out.clear();
  for (double a : p.real) out.push_back(1.0 / (s - a));
  for (cd a : p.pairs) {
    const cd u = 1.0 / (s - a), v = 1.0 / (s - std::conj(a));
    out.push_back(u + v);
    out.push_back(cd(0, 1) * (u - v));
  }
}

Eigen::VectorXd solve_ls(Eigen::MatrixXd a, const Eigen::VectorXd& b) {
  Eigen::VectorXd cs = a.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < cs.size(); ++j)
    if (!(cs[j] > 0)) cs[j] = 1.0;
  a = a * cs.cwiseInverse().asDiagonal();
  Eigen::VectorXd x = a.colPivHouseholderQr().solve(b);
  return x.cwiseQuotient(cs);
}

// New poles: zeros of σ(s) = 1 + Σ c̃ φ(s) = eig(A − b·c̃ᵀ), unstable ones reflected.
PoleSet relocate(const PoleSet& p, const Eigen::VectorXd& ct, double rmax) {
  const int n = p.columns();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  int i = 0;
  for (double r : p.real) {
    a(i, i) = r;
    b(i) = 1.0;
    ++i;
  }
  for (cd q : p.pairs) {
    a(i, i) = q.real();
    a(i, i + 1) = q.imag();
    a(i + 1, i) = -q.imag();
    a(i + 1, i + 1) = q.real();
    b(i) = 2.0;
    i += 2;
  }
  const Eigen::MatrixXd m = a - b * ct.transpose();
  Eigen::EigenSolver<Eigen::MatrixXd> es(m, false);
  PoleSet out;
  for (Eigen::Index k = 0; k < es.eigenvalues().size(); ++k) {
    cd z = es.eigenvalues()[k];
    if (z.real() > 0) z = cd(-z.real(), z.imag());  // reflect into the left half-plane
    if (z.real() == 0) z = cd(-1e-9, z.imag());
    if (rmax > 0 && std::abs(z) > rmax)
      z *= rmax / std::abs(z);  // normalised units: ω_s = 2π·f_max
    if (std::abs(z.imag()) < 1e-12 * std::max(1.0, std::abs(z)))
      out.real.push_back(z.real());
    else if (z.imag() > 0)
      out.pairs.push_back(z);
  }
  // A lone complex eigenvalue without its conjugate cannot happen for a real matrix,
  // but rounding may split a near-real pair: keep the count.
  while (out.count() < n) out.real.push_back(-1.0);
  return out;
}
}  // namespace

cd VectorFit::eval(cd s) const {
  cd v = d + s * e;
  for (Eigen::Index k = 0; k < poles.size(); ++k) v += residues[k] / (s - poles[k]);
  return v;
}

VectorFit vector_fit(const Eigen::VectorXd& f, const Eigen::VectorXcd& h,
                     const Eigen::VectorXd& weights, const VectorFitOptions& opt) {
  const char* who = "vector_fit";
  const Eigen::Index n = f.size();
  if (h.size() != n || (weights.size() && weights.size() != n))
    throw std::invalid_argument(std::string(who) + ": f, H and weights differ in length");
  if (opt.pole_pairs < 1 || opt.iterations < 1)
    throw std::invalid_argument(std::string(who) + ": need >= 1 pole pair and iteration");
  const int np = 2 * opt.pole_pairs;
  const int nextra = int(opt.proper_term) + int(opt.slope_term);
  if (2 * n < 2 * np + nextra + 2)
    throw std::invalid_argument(std::string(who) + ": " + std::to_string(n) +
                                " samples are too few for " + std::to_string(opt.pole_pairs) +
                                " pole pairs");
  double fmin = f.minCoeff(), fmax = f.maxCoeff();
  if (!(fmin >= 0) || !(fmax > 0))
    throw std::invalid_argument(std::string(who) + ": frequencies must be >= 0, not all 0");
  for (Eigen::Index k = 0; k < n; ++k)
    if (!std::isfinite(h[k].real()) || !std::isfinite(h[k].imag()))
      throw std::invalid_argument(std::string(who) + ": non-finite sample at " +
                                  std::to_string(f[k]) + " Hz");
  const double ws = kTwoPi * fmax;
  std::vector<cd> s(static_cast<std::size_t>(n));
  Eigen::VectorXd w(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    s[static_cast<std::size_t>(k)] = cd(0.0, kTwoPi * f[k] / ws);
    w[k] = weights.size() ? weights[k] : 1.0 / std::max(std::abs(h[k]), 1e-300);
  }
  // Starting poles: pairs spread linearly over the band, lightly damped (β/100).
  PoleSet poles;
  const double lo = std::max(fmin, fmax / 100.0) / fmax;
  for (int i = 0; i < opt.pole_pairs; ++i) {
    const double b =
        lo + (1.0 - lo) * (opt.pole_pairs == 1 ? 0.5 : double(i) / (opt.pole_pairs - 1));
    poles.pairs.push_back(cd(-b / 100.0, b));
  }
  std::vector<cd> phi;
  for (int it = 0; it < opt.iterations; ++it) {
    const int nc = poles.columns();
    const int nu = 2 * nc + nextra;
    Eigen::MatrixXd a(2 * n, nu);
    Eigen::VectorXd b(2 * n);
    for (Eigen::Index k = 0; k < n; ++k) {
      const cd sk = s[static_cast<std::size_t>(k)];
      basis_row(poles, sk, phi);
      std::vector<cd> row(static_cast<std::size_t>(nu));
      for (int j = 0; j < nc; ++j)
        row[static_cast<std::size_t>(j)] = phi[static_cast<std::size_t>(j)];
      int c = nc;
      if (opt.proper_term) row[static_cast<std::size_t>(c++)] = 1.0;
      if (opt.slope_term) row[static_cast<std::size_t>(c++)] = sk;
      for (int j = 0; j < nc; ++j)
        row[static_cast<std::size_t>(c + j)] = -h[k] * phi[static_cast<std::size_t>(j)];
      for (int j = 0; j < nu; ++j) {
        a(2 * k, j) = row[static_cast<std::size_t>(j)].real() * w[k];
        a(2 * k + 1, j) = row[static_cast<std::size_t>(j)].imag() * w[k];
      }
      b(2 * k) = h[k].real() * w[k];
      b(2 * k + 1) = h[k].imag() * w[k];
    }
    const Eigen::VectorXd x = solve_ls(a, b);
    poles = relocate(poles, x.tail(nc), opt.max_pole_ratio);
  }
  // Residues, d and e with the final poles.
  const int nc = poles.columns();
  const int nu = nc + nextra;
  Eigen::MatrixXd a(2 * n, nu);
  Eigen::VectorXd b(2 * n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const cd sk = s[static_cast<std::size_t>(k)];
    basis_row(poles, sk, phi);
    int c = 0;
    for (; c < nc; ++c) {
      a(2 * k, c) = phi[static_cast<std::size_t>(c)].real() * w[k];
      a(2 * k + 1, c) = phi[static_cast<std::size_t>(c)].imag() * w[k];
    }
    if (opt.proper_term) a(2 * k, c) = w[k], a(2 * k + 1, c) = 0.0, ++c;
    if (opt.slope_term) a(2 * k, c) = 0.0, a(2 * k + 1, c) = sk.imag() * w[k], ++c;
    b(2 * k) = h[k].real() * w[k];
    b(2 * k + 1) = h[k].imag() * w[k];
  }
  const Eigen::VectorXd x = solve_ls(a, b);
  // Back to physical units: r'/(s' − a') = r'·ω_s/(s − a'·ω_s), e'·s' = (e'/ω_s)·s.
  VectorFit out;
  out.poles.resize(poles.count());
  out.residues.resize(poles.count());
  int i = 0, c = 0;
  for (double r : poles.real) {
    out.poles[i] = r * ws;
    out.residues[i] = x[c] * ws;
    ++i, ++c;
  }
  for (cd q : poles.pairs) {
    const cd res(x[c], x[c + 1]);
    out.poles[i] = q * ws;
    out.residues[i] = res * ws;
    out.poles[i + 1] = std::conj(q) * ws;
    out.residues[i + 1] = std::conj(res) * ws;
    i += 2;
    c += 2;
  }
  if (opt.proper_term) out.d = x[c++];
  if (opt.slope_term) out.e = x[c++] / ws;
  return out;
}

}  // namespace piezo::dsp
