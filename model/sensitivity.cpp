#include "model/sensitivity.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "model/modal.hpp"

namespace piezo::model {

namespace {

// All modes up to f_max: doubles the mode count until the highest computed
// mode lies above f_max (or every mode is computed).
ModalResult modes_up_to(ModalSolver& s, const PiezoMaterialE& m, Electrodes e, double f_max,
                        const SensitivityOptions& o, SensitivityResult& res) {
  const int n_max = s.model().n_u() - 1;
  ModalOptions mo;
  mo.active_coupling = o.active_coupling;
  mo.active_coupling_open = o.active_coupling_open;
  mo.n_modes = std::min(20, n_max);
  for (;;) {
    ModalResult r = s.solve(m, e, mo);
    if (!r.converged && res.converged) {
      res.converged = false;
      res.message = std::string(to_string(e)) + ": " + r.message;
    }
    const bool covers = !r.modes.empty() && r.modes.back().frequency_hz > f_max;
    if (covers || !r.converged || mo.n_modes >= n_max) return r;
    mo.n_modes = std::min(2 * mo.n_modes, n_max);
  }
}

std::vector<int> active_in_band(const ModalResult& r, double band_hz) {
  std::vector<int> idx;
  for (std::size_t k = 0; k < r.modes.size(); ++k)
    if (r.modes[k].electrically_active && r.modes[k].frequency_hz < band_hz)
      idx.push_back(static_cast<int>(k));
  return idx;
}

std::vector<double> frequencies(const ModalResult& r, const std::vector<int>& idx) {
  std::vector<double> f;
  for (int k : idx) f.push_back(r.modes[k].frequency_hz);
  return f;
}

// Each nominal active mode → the symmetric perturbed mode of largest MAC.
std::vector<TrackedMode> track(const ModalResult& nominal, const std::vector<int>& active,
                               const ModalResult& perturbed, const SpMat& m) {
  std::vector<TrackedMode> out;
  const Eigen::MatrixXd mp = m * perturbed.shapes;
  for (int k : active) {
    const Eigen::RowVectorXd overlap = nominal.shapes.col(k).transpose() * mp;
    TrackedMode t;
    t.nominal_hz = nominal.modes[k].frequency_hz;
    for (std::size_t j = 0; j < perturbed.modes.size(); ++j) {
      if (perturbed.modes[j].symmetric_fraction < 0.5) continue;
      const double mac =
          overlap[static_cast<Eigen::Index>(j)] * overlap[static_cast<Eigen::Index>(j)];
      if (mac > t.mac) {
        t.mac = mac;
        t.perturbed_hz = perturbed.modes[j].frequency_hz;
      }
    }
    t.change = t.perturbed_hz / t.nominal_hz - 1.0;
    out.push_back(t);
  }
  return out;
}

// Parameter `index` of `form` scaled by `factor`, in the d form (the d and
// engineering forms) — the FE model's e form follows by to_e_form.
PiezoMaterialD scaled_d(const PiezoMaterialD& base, SensitivityForm form, int index, double factor) {
  PiezoMaterialD m = base;
  if (form == SensitivityForm::engineering && index < 5) {
    EngineeringConstants ec = engineering_constants(base);
    double* field[5] = {&ec.y_e11, &ec.y_e33, &ec.nu12, &ec.nu13, &ec.g};
    *field[index] *= factor;
    return with_engineering_constants(base, ec);
  }
  d_param(m, static_cast<DParam>(index)) *= factor;  // the d form, and the engineering form's last five
  return m;
}

double& e_param(PiezoMaterialE& m, int index) {
  double* field[kNumDParams] = {&m.c_e11, &m.c_e12, &m.c_e13, &m.c_e33, &m.c_e44,
                                &m.e31,   &m.e33,   &m.e15,   &m.eps_s11, &m.eps_s33};
  return *field[index];
}

}  // namespace

const char* d_param_name(DParam p) {
  static constexpr const char* names[kNumDParams] = {"sE11", "sE12", "sE13", "sE33",   "sE44",
                                                     "d31",  "d33",  "d15",  "epsT11", "epsT33"};
  return names[static_cast<int>(p)];
}

double& d_param(PiezoMaterialD& m, DParam p) {
  switch (p) {
    case DParam::s_e11:
      return m.s_e11;
    case DParam::s_e12:
      return m.s_e12;
    case DParam::s_e13:
      return m.s_e13;
    case DParam::s_e33:
      return m.s_e33;
    case DParam::s_e44:
      return m.s_e44;
    case DParam::d31:
      return m.d31;
    case DParam::d33:
      return m.d33;
    case DParam::d15:
      return m.d15;
    case DParam::eps_t11:
      return m.eps_t11;
    case DParam::eps_t33:
      return m.eps_t33;
  }
  throw std::invalid_argument("d_param: unknown parameter");
}

bool seed_says_sensitive(DParam p) {
  return p == DParam::s_e11 || p == DParam::s_e12 || p == DParam::d31 || p == DParam::eps_t33;
}

const char* to_string(SensitivityForm f) {
  switch (f) {
    case SensitivityForm::d:
      return "d";
    case SensitivityForm::engineering:
      return "engineering";
    case SensitivityForm::e:
      return "e";
  }
  return "?";
}

const std::vector<SensitivityParam>& sensitivity_params(SensitivityForm f) {
  using G = ParamGroup;
  static const std::vector<SensitivityParam> d = {
      {"sE11", G::elastic, true},  {"sE12", G::elastic, true},        {"sE13", G::elastic, false},
      {"sE33", G::elastic, false}, {"sE44", G::elastic, false},       {"d31", G::piezoelectric, true},
      {"d33", G::piezoelectric, false}, {"d15", G::piezoelectric, false}, {"epsT11", G::dielectric, false},
      {"epsT33", G::dielectric, true}};
  static const std::vector<SensitivityParam> eng = {
      {"YE11", G::elastic, true},  {"YE33", G::elastic, false},       {"nu12", G::elastic, true},
      {"nu13", G::elastic, false}, {"G", G::elastic, false},          {"d31", G::piezoelectric, true},
      {"d33", G::piezoelectric, false}, {"d15", G::piezoelectric, false}, {"epsT11", G::dielectric, false},
      {"epsT33", G::dielectric, true}};
  static const std::vector<SensitivityParam> e = {
      {"cE11", G::elastic, true},  {"cE12", G::elastic, true},        {"cE13", G::elastic, true},
      {"cE33", G::elastic, true},  {"cE44", G::elastic, false},       {"e31", G::piezoelectric, true},
      {"e33", G::piezoelectric, true}, {"e15", G::piezoelectric, false}, {"epsS11", G::dielectric, false},
      {"epsS33", G::dielectric, true}};
  switch (f) {
    case SensitivityForm::d:
      return d;
    case SensitivityForm::engineering:
      return eng;
    case SensitivityForm::e:
      return e;
  }
  throw std::invalid_argument("sensitivity_params: unknown form");
}

double seed_factor(ParamGroup g) { return g == ParamGroup::elastic ? 2.0 : 0.5; }

void SensitivityOptions::validate() const {
  const std::string fn = "SensitivityOptions::validate: ";
  if (!(band_hz > 0) || !std::isfinite(band_hz))
    throw std::invalid_argument(fn + "band_hz must be finite and > 0");
  if (factors.empty()) throw std::invalid_argument(fn + "no factors");
  for (double f : factors)
    if (!(f > 0) || !std::isfinite(f) || f == 1.0)
      throw std::invalid_argument(fn + "factors must be finite, > 0 and != 1");
  if (!(active_coupling >= 0) || !(active_coupling_open >= 0))
    throw std::invalid_argument(fn + "active_coupling(_open) must be >= 0");
  if (!(track_margin >= 1) || !std::isfinite(track_margin))
    throw std::invalid_argument(fn + "track_margin must be finite and >= 1");
  mesh.validate();
}

double SensitivityResult::max_change(DParam p) const {
  double m = 0;
  for (const auto& c : cases)
    if (c.param == p && c.valid) m = std::max(m, c.max_abs_change);
  return m;
}

int SensitivityResult::valid_cases(DParam p) const {
  int n = 0;
  for (const auto& c : cases) n += c.param == p && c.valid;
  return n;
}

namespace {

SensitivityResult study(const TubeGeometry& geometry, const PiezoMaterialD& material,
                        const SensitivityOptions& options, const char* fn) {
  options.validate();
  geometry.validate();
  PiezoMaterialE nominal_e;
  try {
    nominal_e = to_e_form(material);
    validate(nominal_e, fn);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(fn) + ": nominal material: " + e.what());
  }
  TubeModel tm(geometry, options.mesh);
  ModalSolver solver(tm);
  SensitivityResult res;
  const double band = options.band_hz, reach = options.track_margin * options.band_hz;
  const auto sc0 = modes_up_to(solver, nominal_e, Electrodes::short_circuit, band, options, res);
  const auto oc0 = modes_up_to(solver, nominal_e, Electrodes::open_circuit, band, options, res);
  const auto sc0_active = active_in_band(sc0, band), oc0_active = active_in_band(oc0, band);
  res.nominal = {frequencies(sc0, sc0_active), frequencies(oc0, oc0_active),
                 solver.static_capacitance(nominal_e)};
  const auto& params = sensitivity_params(options.form);
  for (int i = 0; i < static_cast<int>(params.size()); ++i) {
    const std::vector<double> factors =
        options.seed_protocol ? std::vector<double>{seed_factor(params[static_cast<std::size_t>(i)].group)}
                              : options.factors;
    for (double factor : factors) {
      SensitivityCase c;
      c.param = static_cast<DParam>(i);
      c.index = i;
      c.name = params[static_cast<std::size_t>(i)].name;
      c.factor = factor;
      PiezoMaterialE e;
      try {  // e.g. sE11 halved: sE not positive definite; d31 doubled: coupling > 1
        if (options.form == SensitivityForm::e) {
          e = nominal_e;
          e_param(e, i) *= factor;
        } else {
          e = to_e_form(scaled_d(material, options.form, i, factor));
        }
        validate(e, fn);
      } catch (const std::invalid_argument& ex) {
        c.physical = false;
        c.reason = ex.what();
        if (!options.seed_protocol) {
          res.cases.push_back(std::move(c));
          continue;
        }
        try {  // the seed solved it anyway: so do we, flagged
          if (options.form != SensitivityForm::e) e = to_e_form_unchecked(scaled_d(material, options.form, i, factor));
          validate_finite(e, fn);
        } catch (const std::invalid_argument& ex2) {
          c.reason += std::string("; not solvable either: ") + ex2.what();
          res.cases.push_back(std::move(c));
          continue;
        }
      }
      solver.set_physical_checks(c.physical);
      // A non-physical case's non-convergence is its own (its reason), not the study's.
      SensitivityResult scratch;
      SensitivityResult& book = c.physical ? res : scratch;
      try {
        const auto sc = modes_up_to(solver, e, Electrodes::short_circuit, reach, options, book);
        const auto oc = modes_up_to(solver, e, Electrodes::open_circuit, reach, options, book);
        c.perturbed = {frequencies(sc, active_in_band(sc, band)),
                       frequencies(oc, active_in_band(oc, band)), solver.static_capacitance(e)};
        c.short_modes = track(sc0, sc0_active, sc, tm.split().m);
        c.open_modes = track(oc0, oc0_active, oc, tm.split().m);
      } catch (const std::exception& ex) {  // a non-physical material the solver cannot take
        solver.set_physical_checks(true);
        if (c.physical) throw;
        c.reason += std::string("; its FE solve failed: ") + ex.what();
        res.cases.push_back(std::move(c));
        continue;
      }
      solver.set_physical_checks(true);
      if (!scratch.converged) c.reason += "; its modal solve did not converge: " + scratch.message;
      c.solved = true;
      c.valid = c.physical;
      c.c_static_change = c.perturbed.c_static_f / res.nominal.c_static_f - 1.0;
      c.max_abs_change = std::abs(c.c_static_change);
      for (const auto* v : {&c.short_modes, &c.open_modes})
        for (const auto& t : *v) {
          c.max_abs_change = std::max(c.max_abs_change, std::abs(t.change));
          c.min_mac = std::min(c.min_mac, t.mac);
        }
      res.cases.push_back(std::move(c));
    }
  }
  return res;
}

}  // namespace

SensitivityResult d_form_sensitivity(const TubeGeometry& geometry, const PiezoMaterialD& material,
                                     const SensitivityOptions& options) {
  SensitivityOptions o = options;
  o.form = SensitivityForm::d;
  return study(geometry, material, o, "d_form_sensitivity");
}

SensitivityResult form_sensitivity(const TubeGeometry& geometry, const PiezoMaterialD& material,
                                   const SensitivityOptions& options) {
  return study(geometry, material, options, "form_sensitivity");
}

}  // namespace piezo::model
