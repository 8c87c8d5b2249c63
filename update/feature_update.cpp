#include "update/feature_update.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "dsp/signal_stats.hpp"

namespace piezo::update {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const char* const kNames[4] = {"YE11", "nu12", "d31", "epsT33_rel"};
const char* const kUnits[4] = {"Pa", "-", "C/N", "-"};

std::string fmt(const char* f, double a) {
  char b[96];
  std::snprintf(b, sizeof b, f, a);
  return b;
}

std::array<double, 4> as_array(const TubeParams& p) { return {p.y_e11, p.nu12, p.d31, p.eps_t33}; }

TubeParams scaled(const TubeParams& p, const Eigen::Vector4d& x) {  // p·e^x (sign of d31 kept)
  TubeParams q = p;
  q.y_e11 *= std::exp(x[0]);
  q.nu12 *= std::exp(x[1]);
  q.d31 *= std::exp(x[2]);
  q.eps_t33 *= std::exp(x[3]);
  return q;
}

// The features of a model: nr resonances, na anti-resonances (electrically
// active, ascending) and the capacitance at f_L.
struct ModelFeatures {
  bool ok = false;
  std::string why;
  std::vector<double> res, anti;
  double c = 0;
};

ModelFeatures model_features(model::ModalSolver& solver, const MaterialClass& cls, const TubeParams& p, int nr,
                             int na, double f_l, const model::ModalOptions& mo) {
  ModelFeatures out;
  try {
    const auto mat = cls.e_form(p);
    const auto f = model_frequencies(solver, mat, nr, na, mo);
    if (static_cast<int>(f.resonances_hz.size()) < nr || static_cast<int>(f.antiresonances_hz.size()) < na) {
      out.why = "fewer electrically active model modes than measured features";
      return out;
    }
    out.res = f.resonances_hz;
    out.anti = f.antiresonances_hz;
    out.c = model_capacitance(solver, mat, f_l, mo);
    out.ok = true;
  } catch (const std::exception& e) {
    out.why = e.what();
  }
  return out;
}

// Measured values and σ's in the order resonances, anti-resonances, capacitance.
void measured_vectors(const MeasuredFeatures& mf, std::vector<double>& y, std::vector<double>& s) {
  y.clear();
  s.clear();
  for (std::size_t i = 0; i < mf.resonances_hz.size(); ++i) {
    y.push_back(mf.resonances_hz[i]);
    s.push_back(i < mf.resonance_sigma_hz.size() ? mf.resonance_sigma_hz[i] : NAN);
  }
  for (std::size_t i = 0; i < mf.antiresonances_hz.size(); ++i) {
    y.push_back(mf.antiresonances_hz[i]);
    s.push_back(i < mf.antiresonance_sigma_hz.size() ? mf.antiresonance_sigma_hz[i] : NAN);
  }
  const double c = mf.low_frequency_capacitance();
  y.push_back(c);
  s.push_back(mf.low_z_sigma_ohm > 0 ? c * mf.low_z_sigma_ohm / mf.low_z_ohm : NAN);
}

// The least-squares bound on the constants' σ (absolute), from the features'
// σ's and the FE model's sensitivities at p; inf where the features do not
// determine a constant. Empty optional when the model cannot be evaluated.
std::optional<std::array<double, 4>> fisher_sigma(model::ModalSolver& solver, const MaterialClass& cls,
                                                  const TubeParams& p, const MeasuredFeatures& mf,
                                                  const model::ModalOptions& mo, std::string& why) {
  std::vector<double> y, s;
  measured_vectors(mf, y, s);
  const int nr = static_cast<int>(mf.resonances_hz.size()), na = static_cast<int>(mf.antiresonances_hz.size());
  const int n = static_cast<int>(y.size());
  Eigen::MatrixXd a(n, 4);
  const double h = 1e-4;
  for (int k = 0; k < 4; ++k) {
    Eigen::Vector4d x = Eigen::Vector4d::Zero();
    x[k] = h;
    const auto up = model_features(solver, cls, scaled(p, x), nr, na, mf.low_z_hz, mo);
    x[k] = -h;
    const auto dn = model_features(solver, cls, scaled(p, x), nr, na, mf.low_z_hz, mo);
    if (!up.ok || !dn.ok) {
      why = up.ok ? dn.why : up.why;
      return std::nullopt;
    }
    auto vec = [&](const ModelFeatures& m) {
      std::vector<double> v = m.res;
      v.insert(v.end(), m.anti.begin(), m.anti.end());
      v.push_back(m.c);
      return v;
    };
    const auto vu = vec(up), vd = vec(dn);
    for (int i = 0; i < n; ++i) a(i, k) = std::log(vu[i] / vd[i]) / (2 * h) / (s[i] / y[i]);
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
  const auto& sv = svd.singularValues();
  const auto& v = svd.matrixV();
  std::array<double, 4> out{};
  const auto pv = as_array(p);
  for (int k = 0; k < 4; ++k) {
    double var = 0;
    for (int j = 0; j < 4; ++j) {
      const bool null = j >= sv.size() || !(sv[j] > 1e-9 * sv[0]);
      if (null) {
        if (std::abs(v(k, j)) > 1e-6) var = kInf;
      } else {
        var += v(k, j) * v(k, j) / (sv[j] * sv[j]);
      }
    }
    out[static_cast<std::size_t>(k)] = std::abs(pv[static_cast<std::size_t>(k)]) * std::sqrt(var);
  }
  return out;
}

// εT33 with the other constants at p0 such that the FE model's C(f_L) is the measured one.
std::pair<double, double> eps_from_capacitance(model::ModalSolver& solver, const MaterialClass& cls,
                                               const TubeParams& p0, const MeasuredFeatures& mf,
                                               const model::ModalOptions& mo) {
  TubeParams p = p0;
  const double c_meas = mf.low_frequency_capacitance();
  for (int k = 0; k < 6; ++k) {
    const double c = model_capacitance(solver, cls.e_form(p), mf.low_z_hz, mo);
    const double ratio = c_meas / c;
    p.eps_t33 *= ratio;
    if (std::abs(ratio - 1) < 1e-10) break;
  }
  const double rel = mf.low_z_sigma_ohm > 0 ? mf.low_z_sigma_ohm / mf.low_z_ohm : NAN;
  return {p.eps_t33, p.eps_t33 * rel};
}

bool has_sigma(const std::vector<double>& s, std::size_t i) { return i < s.size() && std::isfinite(s[i]) && s[i] > 0; }

}  // namespace

const char* to_string(FeatureMethod m) { return m == FeatureMethod::cmcm ? "cmcm" : "lm"; }

FeatureCheck check_feature_update(const FeatureCheckInput& in, const FeatureCheckOptions& opt) {
  FeatureCheck out;
  const auto& mf = in.measured;
  const auto pv = as_array(in.updated);
  auto constants = [&](double widen) {
    out.constants.clear();
    for (std::size_t k = 0; k < 4; ++k) {
      ConstantEstimate c;
      c.name = kNames[k];
      c.unit = kUnits[k];
      const double scale = k == 3 ? 1.0 / model::kEps0 : 1.0;
      c.value = pv[k] * scale;
      c.sigma_statistical = in.sigma[k] * scale;
      c.sigma = c.sigma_statistical * widen;
      c.status = "ok";
      if (!std::isfinite(c.sigma)) {
        c.status = "not identifiable";
        c.reason = "the features do not determine it";
      } else if (std::abs(c.sigma / c.value) > opt.max_relative_sigma) {
        c.status = "not identifiable";
        c.reason = "relative sigma " + fmt("%.3g", 100 * std::abs(c.sigma / c.value)) + " % above " +
                   fmt("%.3g", 100 * opt.max_relative_sigma) + " %";
      }
      out.constants.push_back(c);
    }
  };
  constants(1.0);
  auto refuse = [&](const std::string& status, const std::string& reason) {
    out.status = status;
    out.reason = reason;
    for (auto& c : out.constants)
      if (c.status == "ok") {
        c.status = "not identifiable";
        c.reason = "the update is refused (" + status + ")";
      }
    return out;
  };

  // 1. The features: some, in the band, each with a σ.
  if (mf.resonances_hz.empty() && mf.antiresonances_hz.empty())
    return refuse("no_features", "no resonance or anti-resonance in " + fmt("%.4g", in.band.lo_hz) + "-" +
                                     fmt("%.4g Hz", in.band.hi_hz));
  auto check_list = [&](const std::vector<double>& f, const std::vector<double>& s, const char* what) -> std::string {
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (!in.band.contains(f[i]))
        return std::string(what) + " " + fmt("%.6g Hz", f[i]) + " lies outside the band " + fmt("%.4g", in.band.lo_hz) +
               "-" + fmt("%.4g Hz", in.band.hi_hz) + (in.band.source.empty() ? "" : " (" + in.band.source + ")");
      if (!has_sigma(s, i)) return std::string(what) + " " + fmt("%.6g Hz", f[i]) + " was measured without a sigma";
    }
    return "";
  };
  for (const auto& why : {check_list(mf.resonances_hz, mf.resonance_sigma_hz, "resonance"),
                          check_list(mf.antiresonances_hz, mf.antiresonance_sigma_hz, "anti-resonance")})
    if (!why.empty()) return refuse("no_features", why);
  if (!(mf.low_z_sigma_ohm > 0) || !std::isfinite(mf.low_z_sigma_ohm))
    return refuse("no_features", "the low-frequency impedance was measured without a sigma");

  // 2. The method's own verdict.
  if (in.method_status != "converged")
    return refuse(in.method_status, in.method_message.empty() ? "the method did not converge" : in.method_message);

  // 3. Physics.
  {
    const auto& b = opt.bounds;
    const auto& p = in.updated;
    const double eps_rel = p.eps_t33 / model::kEps0;
    const double k31 = p.eps_t33 > 0 && p.y_e11 > 0 ? std::abs(p.d31) * std::sqrt(p.y_e11 / p.eps_t33) : NAN;
    std::string why;
    if (!(p.y_e11 >= b.y_e11_min && p.y_e11 <= b.y_e11_max))
      why = "YE11 " + fmt("%.4g Pa", p.y_e11) + " outside " + fmt("%.3g", b.y_e11_min) + "-" + fmt("%.3g Pa", b.y_e11_max);
    else if (!(p.nu12 > b.nu12_min && p.nu12 < b.nu12_max))
      why = "nu12 " + fmt("%.4g", p.nu12) + " outside " + fmt("%.3g", b.nu12_min) + "-" + fmt("%.3g", b.nu12_max);
    else if (!(std::abs(p.d31) >= b.d31_abs_min && std::abs(p.d31) <= b.d31_abs_max))
      why = "|d31| " + fmt("%.4g C/N", std::abs(p.d31)) + " outside " + fmt("%.3g", b.d31_abs_min) + "-" +
            fmt("%.3g C/N", b.d31_abs_max);
    else if (!(eps_rel >= b.eps_t33_rel_min && eps_rel <= b.eps_t33_rel_max))
      why = "epsT33 " + fmt("%.5g eps0", eps_rel) + " outside " + fmt("%.4g", b.eps_t33_rel_min) + "-" +
            fmt("%.4g eps0", b.eps_t33_rel_max);
    else if (!(k31 <= b.k31_max))
      why = "coupling k31 = |d31| sqrt(YE11/epsT33) = " + fmt("%.3g", k31) + " above " + fmt("%.3g", b.k31_max);
    if (!why.empty()) return refuse("non_physical", why + " (" + b.material_class + ")");
  }

  // 4. The features explained: χ² of the residuals against their σ.
  if (in.model_resonances_hz.size() < mf.resonances_hz.size() ||
      in.model_antiresonances_hz.size() < mf.antiresonances_hz.size() || !(in.model_capacitance_f > 0))
    return refuse("not_identifiable", "the updated model has fewer active modes than measured features");
  std::vector<double> y, s;
  measured_vectors(mf, y, s);
  std::vector<double> m = in.model_resonances_hz;
  m.resize(mf.resonances_hz.size());
  for (std::size_t i = 0; i < mf.antiresonances_hz.size(); ++i) m.push_back(in.model_antiresonances_hz[i]);
  m.push_back(in.model_capacitance_f);
  const FeatureResidual* worst = nullptr;
  for (std::size_t i = 0; i < y.size(); ++i) {
    FeatureResidual r;
    const std::size_t nr = mf.resonances_hz.size(), na = mf.antiresonances_hz.size();
    r.kind = i < nr ? "resonance" : i < nr + na ? "antiresonance" : "capacitance";
    r.index = static_cast<int>(i < nr ? i : i < nr + na ? i - nr : 0);
    r.measured = y[i];
    r.sigma = s[i];
    r.model = m[i];
    r.z = (m[i] - y[i]) / s[i];
    out.chi2 += r.z * r.z;
    out.residuals.push_back(r);
  }
  for (const auto& r : out.residuals)
    if (!worst || std::abs(r.z) > std::abs(worst->z)) worst = &r;
  out.dof = static_cast<int>(y.size()) - in.fitted;
  bool explained = true;
  if (out.dof >= 1) {
    out.log10_chance = dsp::log_gamma_tail((out.dof + 1) / 2, 0.5 * out.chi2) / std::log(10.0);
    explained = out.log10_chance >= std::log10(opt.chi2_chance);
  } else {
    explained = !worst || std::abs(worst->z) <= 3.0;
  }
  if (!explained) {
    std::string w;
    if (worst)
      w = "; worst: " + worst->kind + " " + std::to_string(worst->index + 1) + " " +
          (worst->kind == "capacitance" ? fmt("%.5g F", worst->measured) : fmt("%.6g Hz", worst->measured)) +
          " off by " + fmt("%.3g sigma", worst->z);
    const std::string test =
        out.dof >= 1 ? "chi2 " + fmt("%.4g", out.chi2) + " on " + std::to_string(out.dof) + " dof (chance 1e" +
                           fmt("%.1f", out.log10_chance) + " < " + fmt("%.0e", opt.chi2_chance) + ")"
                     : "no degree of freedom left and a residual beyond 3 sigma (chi2 " + fmt("%.4g", out.chi2) + ")";
    return refuse("not_identifiable", "the updated model does not reproduce the measured features: " + test + w);
  }
  if (out.dof >= 1 && out.chi2 > out.dof) {
    out.birge = std::sqrt(out.chi2 / out.dof);
    constants(out.birge);
  }

  // 5. Each constant determined.
  std::string undetermined;
  for (const auto& c : out.constants)
    if (c.status != "ok") undetermined += (undetermined.empty() ? "" : ", ") + c.name + " (" + c.reason + ")";
  if (!undetermined.empty()) {
    out.status = "not_identifiable";
    out.reason = "the features do not determine " + undetermined;
    return out;
  }
  out.status = "converged";
  return out;
}

FeatureUpdate update_from_features(const model::TubeModel& tube, model::ModalSolver& solver,
                                   const MaterialClass& cls, const TubeParams& p0,
                                   const MeasuredFeatures& features, const FeatureBand& band,
                                   FeatureMethod method, const FeatureUpdateOptions& opt,
                                   const std::string& no_features_reason) {
  const auto t0 = std::chrono::steady_clock::now();
  (void)cls.e_form(p0);  // a non-physical p0 throws
  FeatureUpdate u;
  u.method = method;
  u.used = features;
  u.updated = p0;
  const model::ModalOptions& mo = method == FeatureMethod::cmcm ? opt.cmcm.cmcm.modal : opt.lm.modal;
  FeatureCheckInput in;
  in.measured = features;
  in.band = band;
  in.updated = p0;
  in.sigma.fill(kInf);
  const bool have_c = features.low_z_ohm > 0 && features.low_z_hz > 0;
  if (have_c) {
    try {
      std::tie(u.eps_t33_from_c, u.eps_t33_from_c_sigma) = eps_from_capacitance(solver, cls, p0, features, mo);
    } catch (const std::exception&) {
      u.eps_t33_from_c = 0;
    }
  }
  // εT33 alone, from the capacitance: the answer when the resonances fail.
  auto capacitance_only = [&](const std::string& status, const std::string& reason) {
    in.method_status = status;
    in.method_message = reason;
    // A method's own answer stays `updated` (its constants listed as refused);
    // without one, the nominal constants with εT33 from the capacitance.
    if (!u.cmcm && !u.lm && u.eps_t33_from_c > 0) u.updated.eps_t33 = u.eps_t33_from_c;
    in.updated = u.updated;
    u.check = check_feature_update(in, opt.check);
    u.check.status = status;
    u.check.reason = reason;
    for (auto& c : u.check.constants) {
      c.status = "not identifiable";
      c.reason = reason;
    }
    if (u.eps_t33_from_c > 0 && std::isfinite(u.eps_t33_from_c_sigma)) {
      auto& e = u.check.constants[3];
      e.value = u.eps_t33_from_c / model::kEps0;
      e.sigma = e.sigma_statistical = u.eps_t33_from_c_sigma / model::kEps0;
      const bool tight = std::abs(e.sigma / e.value) <= opt.check.max_relative_sigma;
      e.status = tight ? "ok" : "not identifiable";
      e.reason = tight ? "" : "relative sigma of the low-frequency capacitance above the limit";
      e.note = "from the low-frequency capacitance alone (C^T, eq. 201 with the FE capacitance), the other constants nominal";
    }
    u.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return u;
  };
  if (features.resonances_hz.empty() && features.antiresonances_hz.empty())
    return capacitance_only("no_features", no_features_reason.empty() ? "no resonance or anti-resonance in the band"
                                                                      : no_features_reason);
  // The method itself.
  try {
    features.validate();
    if (method == FeatureMethod::cmcm) {
      u.cmcm = update_cmcm(tube, solver, cls, p0, features, opt.cmcm);
      u.method_status = to_string(u.cmcm->status);
      u.method_message = u.cmcm->message;
      u.updated = u.cmcm->updated;
    } else {
      u.lm = update_lm(tube, solver, cls, p0, features, opt.lm);
      u.method_status = to_string(u.lm->status);
      u.method_message = u.lm->message;
      u.updated = u.lm->updated;
    }
  } catch (const std::invalid_argument& e) {
    return capacitance_only("no_features", std::string("the method cannot use these features: ") + e.what());
  }
  if (u.method_status != "converged")
    return capacitance_only(u.method_status, std::string(to_string(method)) + ": " +
                                                 (u.method_message.empty() ? "did not converge" : u.method_message));
  in.updated = u.updated;
  in.method_status = u.method_status;
  in.method_message = u.method_message;
  const int nr = static_cast<int>(features.resonances_hz.size()), na = static_cast<int>(features.antiresonances_hz.size());
  const auto after = model_features(solver, cls, u.updated, nr, na, features.low_z_hz, mo);
  if (after.ok) {
    in.model_resonances_hz = after.res;
    in.model_antiresonances_hz = after.anti;
    in.model_capacitance_f = after.c;
  }
  // σ of the constants.
  std::string why;
  std::vector<double> y, s;
  measured_vectors(features, y, s);
  bool all_sigma = true;
  for (double x : s) all_sigma = all_sigma && std::isfinite(x) && x > 0;
  if (all_sigma && after.ok) {
    const auto fisher = fisher_sigma(solver, cls, u.updated, features, mo, why);
    if (fisher) in.sigma = *fisher;
    if (fisher && method == FeatureMethod::cmcm) {
      // The delta method through CMCM itself: each feature moved by its σ, re-solved from the answer.
      Eigen::Matrix4d cov = Eigen::Matrix4d::Zero();
      const auto pv = as_array(u.updated);
      for (std::size_t i = 0; i < y.size(); ++i) {
        MeasuredFeatures f2 = features;
        if (i < static_cast<std::size_t>(nr)) f2.resonances_hz[i] += s[i];
        else if (i < static_cast<std::size_t>(nr + na)) f2.antiresonances_hz[i - nr] += s[i];
        else f2.low_z_ohm = 1.0 / (2 * M_PI * f2.low_z_hz * (y[i] + s[i]));
        ++u.resolves;
        try {
          f2.validate();
          const auto r2 = update_cmcm(tube, solver, cls, u.updated, f2, opt.cmcm);
          if (!r2.ok()) throw std::invalid_argument(r2.message);
          const auto p2 = as_array(r2.updated);
          Eigen::Vector4d d;
          for (int k = 0; k < 4; ++k) d[k] = p2[static_cast<std::size_t>(k)] - pv[static_cast<std::size_t>(k)];
          cov += d * d.transpose();
        } catch (const std::invalid_argument&) {
          ++u.resolves_failed;
        }
      }
      for (int k = 0; k < 4; ++k) {
        const auto kk = static_cast<std::size_t>(k);
        in.sigma[kk] = u.resolves_failed > 0 ? kInf : std::max(in.sigma[kk], std::sqrt(cov(k, k)));
      }
      if (u.resolves_failed > 0)
        why = std::to_string(u.resolves_failed) + " of " + std::to_string(u.resolves) +
              " re-solves with a feature moved by its sigma failed: the answer is not stable within the features' sigma";
    }
  }
  u.check = check_feature_update(in, opt.check);
  if (!why.empty() && u.check.converged()) {
    u.check.status = "not_identifiable";
    u.check.reason = why;
    for (auto& c : u.check.constants)
      if (c.status == "ok") {
        c.status = "not identifiable";
        c.reason = why;
      }
  }
  // Refused on anything but a constant the features leave open: εT33 still
  // stands on the low-frequency capacitance, the others are not identifiable.
  const bool only_undetermined =
      u.check.status == "not_identifiable" && u.check.reason.rfind("the features do not determine", 0) == 0;
  if (!u.check.converged() && !only_undetermined) {
    const auto keep = u.check;
    capacitance_only(keep.status, keep.reason);
    u.check.residuals = keep.residuals;
    u.check.chi2 = keep.chi2;
    u.check.dof = keep.dof;
    u.check.log10_chance = keep.log10_chance;
  }
  u.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return u;
}

}  // namespace piezo::update
