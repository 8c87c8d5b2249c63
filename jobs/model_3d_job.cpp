// The jobs' room (jobs/): `model three-d` and `model constrained` (see model_3d_job.hpp).
#include "jobs/model_3d_job.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <ostream>
#include <stdexcept>
#include <string>

#include "jobs/job_error.hpp"
#include "jobs/report/plot_cairo.hpp"
#include "model/analytic_ring.hpp"
#include "model/circumferential.hpp"
#include "model/harmonic.hpp"
#include "model/modal.hpp"

namespace piezo::jobs {

namespace {

namespace pm = piezo::model;

// The 2-D model's active-mode rule (ModalOptions::active_coupling{,_open}).
constexpr double kActiveCoupling = 1e-3;

bool active(const pm::CircumferentialMode& m, double c0) {
  return !m.rigid && m.symmetric && c0 > 0 &&
         m.participation * m.participation / (m.omega * m.omega * c0) > kActiveCoupling;
}

std::vector<double> active_hz(const pm::CircumferentialResult& r) {
  std::vector<double> f;
  for (const auto& m : r.modes)
    if (active(m, r.c_clamped)) f.push_back(m.frequency_hz);
  return f;
}

pm::CircumferentialOptions options(const ModelRequest& a, int n, pm::HarmonicFamily fam, pm::Electrodes e,
                                   double fmax_hz, bool constrained = false) {
  pm::CircumferentialOptions o;
  o.n = n;
  o.family = fam;
  o.electrodes = e;
  o.axial_constrained = constrained;
  o.mesh = {a.n_radial, a.n_axial};
  o.max_frequency_hz = fmax_hz;
  return o;
}

std::vector<double> abs_z(const pm::ModalPortModel& port, const std::vector<double>& f, double beta) {
  const auto z = pm::impedance_from_admittance(pm::admittance_modal(port, f, pm::RayleighDamping{0.0, beta}));
  std::vector<double> a(z.size());
  for (std::size_t i = 0; i < z.size(); ++i) a[i] = std::abs(z[i]);
  return a;
}

// max and median |20 log10(a/b)| over the grid, and where the max is.
nlohmann::json db_difference(const std::vector<double>& f, const std::vector<double>& a,
                             const std::vector<double>& b) {
  std::vector<double> d;
  double worst = 0, at = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    const double x = std::abs(20.0 * std::log10(a[i] / b[i]));
    if (!std::isfinite(x)) continue;
    d.push_back(x);
    if (x > worst) worst = x, at = f[i];
  }
  if (d.empty()) return {{"max_abs_db", nullptr}, {"median_abs_db", nullptr}, {"max_at_hz", nullptr}};
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return {{"max_abs_db", worst}, {"median_abs_db", d[d.size() / 2]}, {"max_at_hz", at}};
}

nlohmann::json mode_json(const pm::CircumferentialMode& m, double c0) {
  return {{"frequency_hz", m.frequency_hz},
          {"symmetric", m.symmetric},
          {"radial_share", m.radial_share},
          {"hoop_share", m.hoop_share},
          {"axial_share", m.axial_share},
          {"electrically_active", active(m, c0)}};
}

std::vector<double> grid(double fmin, double fmax, double step) {
  try {
    return pm::frequency_grid(fmin, fmax, step);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("frequency grid: ") + e.what());
  }
}

// The 2-D code's first ten short- and open-circuit modes (sparse Lanczos).
struct TwoD {
  pm::ModalResult sc, oc;
};
TwoD two_d_modes(pm::ModalSolver& s, const pm::PiezoMaterialE& m, const char* command) {
  pm::ModalOptions mo;
  mo.n_modes = 10;
  TwoD t{s.solve(m, pm::Electrodes::short_circuit, mo), s.solve(m, pm::Electrodes::open_circuit, mo)};
  if (!t.sc.converged || !t.oc.converged)
    throw std::runtime_error(std::string(command) + ": the 2-D modal solve did not converge");
  return t;
}

pm::ModalPortModel port_2d(const pm::TubeModel& tm, const pm::PiezoMaterialE& m) {
  pm::ModalSolver s(tm);
  pm::ModalOptions o;
  o.n_modes = 20;  // as `model impedance` (Fig 14)
  auto p = s.port_model(m, o);
  if (!p.converged) throw std::runtime_error("model three-d: the 2-D modal solve did not converge");
  return p;
}

}  // namespace

ThreeDResult run_three_d(ThreeDRequest a, const std::function<void(int, int)>& progress) {
  const auto r = resolve_model(a.model);
  if (!(a.fmax_hz > 0) || !(a.fmax_hz <= 1e7)) throw InputError("--fmax must lie in (0, 1e7] Hz");
  if (a.max_n < 0 || a.max_n > 32) throw InputError("--max-n must lie in 0..32 (0: until a harmonic has no mode below --fmax)");
  if (!(a.beta >= 0)) throw InputError("--rayleigh-beta must be >= 0");
  const auto& geo = a.model.geometry;
  const pm::MeshOptions mesh{a.model.n_radial, a.model.n_axial};
  const int total = a.max_n > 0 ? a.max_n + 2 : 0;
  int done = 0;
  auto tick = [&] {
    ++done;
    if (progress) progress(done, total);
  };

  // Table 3: the 2-D code (sparse Lanczos) and harmonic n = 0 of the 3-D model (dense, all modes).
  pm::TubeModel tm(geo, mesh);
  pm::ModalSolver s2(tm);
  const TwoD two = two_d_modes(s2, r.material, "model three-d");
  const pm::ModalResult &sc2 = two.sc, &oc2 = two.oc;
  const auto sc3 = pm::circumferential_modes(geo, r.material,
                                             options(a.model, 0, pm::HarmonicFamily::cos_family,
                                                     pm::Electrodes::short_circuit, 0.0));
  const auto oc3 = pm::circumferential_modes(geo, r.material,
                                             options(a.model, 0, pm::HarmonicFamily::cos_family,
                                                     pm::Electrodes::open_circuit, 0.0));
  tick();
  nlohmann::json table = nlohmann::json::array();
  const std::vector<double> f2[2] = {sc2.active_frequencies_hz(), oc2.active_frequencies_hz()};
  const std::vector<double> f3[2] = {active_hz(sc3), active_hz(oc3)};
  for (int c = 0; c < 2; ++c)
    for (std::size_t k = 0; k < std::min({f2[c].size(), f3[c].size(), std::size_t{3}}); ++k)
      table.push_back({{"circuit", c == 0 ? "short" : "open"},
                       {"mode", k + 1},
                       {"two_d_hz", f2[c][k]},
                       {"three_d_hz", f3[c][k]},
                       {"relative_difference", f3[c][k] / f2[c][k] - 1.0}});

  // Every harmonic's modes below fmax: n = 0 (both families), then n = 1, 2, …
  nlohmann::json harmonics = nlohmann::json::array();
  int non_axisymmetric = 0, torsional = 0;
  auto list = [&](const pm::CircumferentialResult& res, const char* note) {
    nlohmann::json modes = nlohmann::json::array();
    int below = 0;
    for (const auto& m : res.modes) {
      if (m.rigid || m.frequency_hz > a.fmax_hz) continue;
      modes.push_back(mode_json(m, res.c_clamped));
      ++below;
    }
    harmonics.push_back({{"n", res.options.n},
                         {"family", pm::to_string(res.options.family)},
                         {"note", note},
                         {"rigid_motions", std::count_if(res.modes.begin(), res.modes.end(),
                                                         [](const auto& m) { return m.rigid; })},
                         {"modes", modes}});
    return below;
  };
  list(sc3, "axisymmetric: the 2-D model (short circuit); the only harmonic that carries charge");
  const auto tors = pm::circumferential_modes(
      geo, r.material, options(a.model, 0, pm::HarmonicFamily::sin_family, pm::Electrodes::short_circuit, a.fmax_hz));
  torsional = list(tors, "torsion (u_theta only), electrically inert");
  tick();
  nlohmann::json torsion = nlohmann::json::array();
  {
    int k = 0;
    for (const auto& m : tors.modes) {
      if (m.rigid) continue;
      if (++k > 3 || m.frequency_hz > a.fmax_hz) break;
      const double exact = pm::torsion_frequency_hz(geo, r.material, k);
      torsion.push_back({{"k", k}, {"fe_hz", m.frequency_hz}, {"exact_hz", exact},
                         {"relative_difference", m.frequency_hz / exact - 1.0}});
    }
  }
  int highest = 0;
  for (int n = 1; n <= (a.max_n > 0 ? a.max_n : 32); ++n) {
    const auto res = pm::circumferential_modes(
        geo, r.material, options(a.model, n, pm::HarmonicFamily::cos_family, pm::Electrodes::short_circuit, a.fmax_hz));
    const int below = list(res, "each mode is a pair (cos and sin families, turned by pi/2n); no charge: "
                                "the full electrodes hold no harmonic n >= 1 of the potential");
    non_axisymmetric += below;
    highest = n;
    tick();
    if (a.max_n == 0 && below == 0) break;
  }

  // Fig 17: |Z| of the 2-D port model (20 modes + residual, as Fig 14) and of
  // the 3-D model (harmonic 0, all modes; n ≥ 1 add no charge).
  const auto f = grid(a.step_hz, a.fmax_hz, a.step_hz);
  ThreeDResult out;
  out.fig17.f_hz = f;
  out.fig17.names = {"two_d", "three_d"};
  out.fig17.abs_z = {abs_z(port_2d(tm, r.material), f, a.beta), abs_z(sc3.port_model(r.material), f, a.beta)};

  nlohmann::json j;
  j["material"] = a.model.material;
  j["model_class"] = r.model_class;
  j["parameters"] = r.parameters;
  j["mesh"] = {{"n_radial", a.model.n_radial}, {"n_axial", a.model.n_axial}};
  j["method"] = "circumferential Fourier harmonics on the 2-D mesh (model/circumferential.hpp)";
  j["fmax_hz"] = a.fmax_hz;
  j["table3"] = table;
  j["torsion_check"] = torsion;
  j["harmonics"] = harmonics;
  j["highest_harmonic"] = highest;
  j["counts_below_fmax"] = {{"axisymmetric_charged", std::count_if(f3[0].begin(), f3[0].end(),
                                                                   [&](double x) { return x <= a.fmax_hz; })},
                            {"torsional", torsional},
                            {"non_axisymmetric_pairs", non_axisymmetric}};
  j["fig17"] = {{"fmin_hz", f.front()}, {"fmax_hz", f.back()}, {"step_hz", a.step_hz},
                {"rayleigh_beta_s", a.beta},
                {"three_d_vs_two_d", db_difference(f, out.fig17.abs_z[1], out.fig17.abs_z[0])}};
  out.json = std::move(j);
  return out;
}

ConstrainedResult run_constrained(ConstrainedRequest a) {
  const auto r = resolve_model(a.model);
  if (!(a.beta >= 0)) throw InputError("--rayleigh-beta must be >= 0");
  const auto f = grid(a.fmin_hz, a.fmax_hz, a.step_hz);
  const auto& geo = a.model.geometry;
  const pm::MeshOptions mesh{a.model.n_radial, a.model.n_axial};
  pm::TubeModel tm(geo, mesh);
  pm::ModalSolver s2(tm);
  const TwoD two = two_d_modes(s2, r.material, "model constrained");
  const pm::ModalResult &sc = two.sc, &oc = two.oc;
  const auto csc = pm::circumferential_modes(
      geo, r.material, options(a.model, 0, pm::HarmonicFamily::cos_family, pm::Electrodes::short_circuit, 0.0, true));
  const auto coc = pm::circumferential_modes(
      geo, r.material, options(a.model, 0, pm::HarmonicFamily::cos_family, pm::Electrodes::open_circuit, 0.0, true));
  const auto ring = pm::analytic_ring(pm::to_d_form(r.material), pm::ring_geometry(geo));

  ConstrainedResult out;
  out.fig19.f_hz = f;
  out.fig19.names = {"free_fe", "constrained_fe", "ring"};
  std::vector<double> zr(f.size());
  for (std::size_t i = 0; i < f.size(); ++i) zr[i] = std::abs(1.0 / pm::ring_admittance(ring, 2.0 * M_PI * f[i]));
  out.fig19.abs_z = {abs_z(port_2d(tm, r.material), f, a.beta), abs_z(csc.port_model(r.material), f, a.beta), zr};

  auto below = [&](std::vector<double> v) {
    v.erase(std::remove_if(v.begin(), v.end(), [&](double x) { return x > a.fmax_hz; }), v.end());
    return v;
  };
  nlohmann::json j;
  j["material"] = a.model.material;
  j["model_class"] = r.model_class;
  j["mesh"] = {{"n_radial", a.model.n_radial}, {"n_axial", a.model.n_axial}};
  j["free_fe"] = {{"short_circuit_hz", below(sc.active_frequencies_hz())},
                  {"open_circuit_hz", below(oc.active_frequencies_hz())}};
  j["constrained_fe"] = {{"short_circuit_hz", below(active_hz(csc))},
                         {"open_circuit_hz", below(active_hz(coc))},
                         {"c_clamped_f", csc.c_clamped},
                         {"note", "u_z = 0 at every node (seed 3.3.1): plane strain along the axis, so the hoop "
                                  "stiffness is cE11-like, not the ring's 1/sE11 (T_zz = 0)"}};
  j["ring"] = {{"resonance_hz", ring.omega_r / (2 * M_PI)},
               {"antiresonance_hz", ring.omega_a / (2 * M_PI)},
               {"k31", ring.k31},
               {"c_free_f", ring.c_free}};
  j["grid"] = {{"fmin_hz", f.front()}, {"fmax_hz", f.back()}, {"step_hz", a.step_hz}, {"rayleigh_beta_s", a.beta}};
  j["constrained_vs_ring"] = db_difference(f, out.fig19.abs_z[1], zr);
  j["free_vs_ring"] = db_difference(f, out.fig19.abs_z[0], zr);
  out.json = std::move(j);
  return out;
}

void write_curves_csv(std::ostream& os, const ImpedanceCurves& c) {
  os << "f_hz";
  for (const auto& n : c.names) os << ',' << n << "_abs_ohm";
  os << '\n';
  char buf[32];
  for (std::size_t i = 0; i < c.f_hz.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.10g", c.f_hz[i]);
    os << buf;
    for (const auto& col : c.abs_z) {
      std::snprintf(buf, sizeof buf, "%.10g", col[i]);
      os << ',' << buf;
    }
    os << '\n';
  }
}

void write_curves_plot(const ImpedanceCurves& c, const std::string& title, const std::string& subtitle,
                       const std::filesystem::path& file) {
  report::Figure fig;
  fig.title = title;
  fig.subtitle = subtitle;
  report::Panel p;
  p.x_label = "frequency";
  p.x_unit = "Hz";
  p.y_label = "|Z|";
  p.y_unit = "Ω";
  p.y_scale = report::Scale::Log;
  const char* colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd"};
  for (std::size_t k = 0; k < c.names.size(); ++k) {
    report::Series s;
    s.label = c.names[k];
    s.x = c.f_hz;
    s.y = c.abs_z[k];
    s.colour = colours[k % 4];
    s.dashed = k == 1;
    p.series.push_back(std::move(s));
  }
  fig.panels.push_back(std::move(p));
  const std::string ext = file.extension().string();
  if (ext == ".svg")
    report::write_svg(fig, file);
  else if (ext == ".png")
    report::write_png(fig, file);
  else
    throw InputError("--plot " + file.string() + ": give a .png or .svg file name");
}

}  // namespace piezo::jobs
