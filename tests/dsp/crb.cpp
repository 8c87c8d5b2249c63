#include "crb.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace piezo::crb {

namespace {
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Parameters: per pole (Re λ[, Im λ]) then per channel per pole (Re r[, Im r]).
struct Layout {
  std::vector<int> width;
  std::vector<std::size_t> lam_at, res_at;
  std::size_t size = 0, channels = 0;
  std::size_t res(std::size_t i, std::size_t c) const {
    return res_at[i] + c * std::size_t(width[i]);
  }
};

Layout layout(const std::vector<cd>& poles, std::size_t nc) {
  Layout l;
  l.channels = nc;
  for (const cd& p : poles) {
    l.width.push_back(p.imag() > 0 ? 2 : 1);
    l.lam_at.push_back(l.size);
    l.size += std::size_t(l.width.back());
  }
  for (std::size_t i = 0; i < poles.size(); ++i) {
    l.res_at.push_back(l.size);
    l.size += nc * std::size_t(l.width[i]);
  }
  return l;
}

Eigen::MatrixXd fisher(const std::vector<cd>& poles, const std::vector<Channel>& ch,
                       const Layout& l, double fs, std::size_t n) {
  const auto p = static_cast<Eigen::Index>(l.size);
  Eigen::MatrixXd f = Eigen::MatrixXd::Zero(p, p);
  Eigen::VectorXd row(p);
  for (std::size_t c = 0; c < ch.size(); ++c) {
    if (ch[c].residue.size() != poles.size())
      throw std::invalid_argument("crb::fisher: one residue per pole and channel");
    const double w = 1.0 / (ch[c].sigma * ch[c].sigma);
    for (std::size_t k = 0; k < n; ++k) {
      const double t = double(k) / fs;
      row.setZero();
      for (std::size_t i = 0; i < poles.size(); ++i) {
        const cd e = std::exp(poles[i] * t), r = ch[c].residue[i];
        const double m = l.width[i] == 2 ? 2.0 : 1.0;  // a pair contributes 2·Re(r e^{λt})
        const auto la = Eigen::Index(l.lam_at[i]), ra = Eigen::Index(l.res(i, c));
        row[la] = m * (r * t * e).real();
        row[ra] = m * e.real();
        if (l.width[i] == 2) {
          row[la + 1] = m * (cd(0, 1) * r * t * e).real();
          row[ra + 1] = m * (cd(0, 1) * e).real();
        }
      }
      f.selfadjointView<Eigen::Lower>().rankUpdate(row, w);
    }
  }
  return f.selfadjointView<Eigen::Lower>();
}

// gᵀ F⁻¹ g over the parameters with free[j], F scaled to unit diagonal before
// the inversion (time constants and residues differ by decades).
double quadratic_form_inverse(const Eigen::MatrixXd& f, const Eigen::VectorXd& g,
                              const std::vector<bool>& free) {
  std::vector<Eigen::Index> idx;
  for (std::size_t j = 0; j < free.size(); ++j)
    if (free[j]) idx.push_back(Eigen::Index(j));
  const auto m = static_cast<Eigen::Index>(idx.size());
  Eigen::MatrixXd fs(m, m);
  Eigen::VectorXd gs(m);
  for (Eigen::Index a = 0; a < m; ++a) {
    gs[a] = g[idx[std::size_t(a)]] / std::sqrt(f(idx[std::size_t(a)], idx[std::size_t(a)]));
    for (Eigen::Index b = 0; b < m; ++b)
      fs(a, b) = f(idx[std::size_t(a)], idx[std::size_t(b)]) /
                 std::sqrt(f(idx[std::size_t(a)], idx[std::size_t(a)]) *
                           f(idx[std::size_t(b)], idx[std::size_t(b)]));
  }
  return gs.dot(fs.ldlt().solve(gs));
}

// V(s), V'(s), V''(s) of one channel's pole–residue sum.
struct Laplace {
  cd v = 0, d1 = 0, d2 = 0;
};

Laplace channel_at(const std::vector<cd>& poles, const Channel& c, const Layout& l, cd s) {
  Laplace out;
  auto add = [&](cd r, cd lam) {
    const cd u = 1.0 / (s - lam);
    out.v += r * u;
    out.d1 -= r * u * u;
    out.d2 += 2.0 * r * u * u * u;
  };
  for (std::size_t i = 0; i < poles.size(); ++i) {
    if (l.width[i] == 2) {
      add(c.residue[i], poles[i]);
      add(std::conj(c.residue[i]), std::conj(poles[i]));
    } else {
      add(c.residue[i].real(), poles[i].real());
    }
  }
  return out;
}

// ∂V/∂θ and ∂V'/∂θ of channel c at s (θ in the full layout).
void channel_gradient(const std::vector<cd>& poles, const Channel& c, std::size_t ci,
                      const Layout& l, cd s, Eigen::VectorXcd& dv, Eigen::VectorXcd& dd1) {
  const auto p = static_cast<Eigen::Index>(l.size);
  dv = Eigen::VectorXcd::Zero(p);
  dd1 = Eigen::VectorXcd::Zero(p);
  const cd j(0, 1);
  for (std::size_t i = 0; i < poles.size(); ++i) {
    const auto la = Eigen::Index(l.lam_at[i]), ra = Eigen::Index(l.res(i, ci));
    if (l.width[i] == 2) {
      const cd r = c.residue[i], rb = std::conj(r);
      const cd u = 1.0 / (s - poles[i]), ub = 1.0 / (s - std::conj(poles[i]));
      dv[la] = r * u * u + rb * ub * ub;
      dv[la + 1] = j * r * u * u - j * rb * ub * ub;
      dd1[la] = -2.0 * (r * u * u * u + rb * ub * ub * ub);
      dd1[la + 1] = -2.0 * (j * r * u * u * u - j * rb * ub * ub * ub);
      dv[ra] = u + ub;
      dv[ra + 1] = j * u - j * ub;
      dd1[ra] = -(u * u + ub * ub);
      dd1[ra + 1] = -(j * u * u - j * ub * ub);
    } else {
      const double r = c.residue[i].real();
      const cd u = 1.0 / (s - poles[i].real());
      dv[la] = r * u * u;
      dd1[la] = -2.0 * r * u * u * u;
      dv[ra] = u;
      dd1[ra] = -u * u;
    }
  }
}

// G = Z'/Z of Z = R1·V2/(V1 − V2), and G'.
struct LogDerivative {
  cd g, dg;
};

LogDerivative log_derivative(const Laplace& a, const Laplace& b) {
  const Laplace d{a.v - b.v, a.d1 - b.d1, a.d2 - b.d2};  // V1 − V2
  const cd q2 = b.d1 / b.v, qd = d.d1 / d.v;
  return {q2 - qd, (b.d2 / b.v - q2 * q2) - (d.d2 / d.v - qd * qd)};
}

// Parameters of the poles marked known (and their residues) left out.
std::vector<bool> free_mask(const std::vector<cd>& poles, const Layout& l,
                            const std::vector<bool>& known) {
  if (!known.empty() && known.size() != poles.size())
    throw std::invalid_argument("crb: `known` needs one flag per pole (or none)");
  std::vector<bool> free(l.size, true);
  for (std::size_t i = 0; i < known.size(); ++i)
    if (known[i])
      for (int q = 0; q < l.width[i]; ++q) {
        free[l.lam_at[i] + std::size_t(q)] = false;
        for (std::size_t c = 0; c < l.channels; ++c) free[l.res(i, c) + std::size_t(q)] = false;
      }
  return free;
}
}  // namespace

double pole_frequency_crb_hz(const std::vector<cd>& poles, const std::vector<Channel>& ch,
                             double fs, std::size_t n, std::size_t index,
                             const std::vector<bool>& known) {
  if (poles[index].imag() <= 0)
    throw std::invalid_argument("pole_frequency_crb_hz: not an oscillating pole");
  if (!known.empty() && known.at(index))
    throw std::invalid_argument("pole_frequency_crb_hz: the pole asked for is flagged known");
  const Layout l = layout(poles, ch.size());
  const Eigen::MatrixXd f = fisher(poles, ch, l, fs, n);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(Eigen::Index(l.size));
  g[Eigen::Index(l.lam_at[index] + 1)] = 1.0 / kTwoPi;
  return std::sqrt(quadratic_form_inverse(f, g, free_mask(poles, l, known)));
}

double divider_feature_hz(const std::vector<cd>& poles, const std::vector<Channel>& ch,
                          double f_start_hz) {
  if (ch.size() != 2) throw std::invalid_argument("divider_feature_hz: channels must be {v1, v2}");
  const Layout l = layout(poles, 2);
  // h(ω) = d ln|Z(jω)|/dω = −Im G(jω), h' = −Re G'(jω); Newton: Δω = −h/h' = −Im G/Re G'.
  double w = kTwoPi * f_start_hz;
  for (int it = 0; it < 50; ++it) {
    const cd s(0, w);
    const auto ld = log_derivative(channel_at(poles, ch[0], l, s), channel_at(poles, ch[1], l, s));
    const double step = -ld.g.imag() / ld.dg.real();
    w += step;
    if (std::abs(step) < 1e-13 * w) return w / kTwoPi;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

Eigen::VectorXd divider_feature_gradient(const std::vector<cd>& poles,
                                         const std::vector<Channel>& ch, double f_hz) {
  if (ch.size() != 2)
    throw std::invalid_argument("divider_feature_gradient: channels must be {v1, v2}");
  const Layout l = layout(poles, 2);
  const cd s(0, kTwoPi * f_hz);
  const Laplace a = channel_at(poles, ch[0], l, s), b = channel_at(poles, ch[1], l, s);
  const auto ld = log_derivative(a, b);
  // ∂G/∂θ = ∂(V2'/V2) − ∂(D'/D), D = V1 − V2.
  Eigen::VectorXcd dv1, dd1, dv2, dd2;
  channel_gradient(poles, ch[0], 0, l, s, dv1, dd1);
  channel_gradient(poles, ch[1], 1, l, s, dv2, dd2);
  const cd dv = a.v - b.v, dd = a.d1 - b.d1;
  const Eigen::VectorXcd dg =
      (dd2 * b.v - b.d1 * dv2) / (b.v * b.v) - ((dd1 - dd2) * dv - dd * (dv1 - dv2)) / (dv * dv);
  // h(ω*, θ) = 0 ⇒ ∂ω*/∂θ = −(∂h/∂θ)/(∂h/∂ω) = −(−Im ∂G)/(−Re G').
  return -dg.imag() / ld.dg.real() / kTwoPi;
}

std::vector<FeatureCrb> divider_feature_crb(const std::vector<cd>& poles,
                                            const std::vector<Channel>& ch, double fs,
                                            std::size_t n, const std::vector<double>& f_start_hz,
                                            const std::vector<bool>& known) {
  const Layout l = layout(poles, 2);
  const Eigen::MatrixXd fi = fisher(poles, ch, l, fs, n);  // once for all features
  const auto free = free_mask(poles, l, known);
  std::vector<FeatureCrb> out;
  for (double f0 : f_start_hz) {
    const double f = divider_feature_hz(poles, ch, f0);
    if (!std::isfinite(f)) {
      out.push_back({f, f});
      continue;
    }
    const Eigen::VectorXd grad = divider_feature_gradient(poles, ch, f);
    out.push_back({f, std::sqrt(quadratic_form_inverse(fi, grad, free))});
  }
  return out;
}

FeatureCrb divider_feature_crb(const std::vector<cd>& poles, const std::vector<Channel>& ch,
                               double fs, std::size_t n, double f_start_hz,
                               const std::vector<bool>& known) {
  return divider_feature_crb(poles, ch, fs, n, std::vector<double>{f_start_hz}, known)[0];
}

std::vector<double> divider_db_crb(const std::vector<cd>& poles, const std::vector<Channel>& ch,
                                   double fs, std::size_t n, const std::vector<double>& f_hz,
                                   const std::vector<bool>& known) {
  if (ch.size() != 2) throw std::invalid_argument("divider_db_crb: channels must be {v1, v2}");
  const Layout l = layout(poles, 2);
  const Eigen::MatrixXd fi = fisher(poles, ch, l, fs, n);
  const auto free = free_mask(poles, l, known);
  std::vector<double> out;
  Eigen::VectorXcd dv1, dd1, dv2, dd2;
  for (double f : f_hz) {
    const cd s(0, kTwoPi * f);
    const Laplace a = channel_at(poles, ch[0], l, s), b = channel_at(poles, ch[1], l, s);
    channel_gradient(poles, ch[0], 0, l, s, dv1, dd1);
    channel_gradient(poles, ch[1], 1, l, s, dv2, dd2);
    // 20·log10|Z| = (20/ln 10)·Re ln(R1·V2/(V1 − V2)).
    const Eigen::VectorXd g =
        (20.0 / std::log(10.0)) * (dv2 / b.v - (dv1 - dv2) / (a.v - b.v)).real();
    out.push_back(std::sqrt(quadratic_form_inverse(fi, g, free)));
  }
  return out;
}

}  // namespace piezo::crb
