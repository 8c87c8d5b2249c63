#include "acquisition/sim_setup.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "acquisition/channel2_response.hpp"
#include "acquisition/divider_state_space.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"

namespace piezo::acq {

namespace {

// The FE tube reduced to its port, in the divider with the circuit effects.
// The drift and step disturbances change the transducer's YE11, εT33 and d31
// between shots: the port model is rebuilt by the same modal solve for the
// scaled material (cached per distinct set of factors; a rebuild costs one
// shift-invert Lanczos solve, ~0.1 s for the default mesh). Scaling follows
// model/material_spec.cpp's overrides: YE11 scales sE11 and sE12 (ν12 kept;
// the isotropic class scales its one Young's modulus), εT33 and d31 scale
// themselves. The fixture, the parasitic branches and the device selection
// stay as they are.
class FePhysics : public drivers::sim::BenchPhysics {
 public:
  struct Transducer {  // what the port model is solved from
    std::unique_ptr<model::TubeModel> tube;
    std::unique_ptr<model::ModalSolver> solver;  // refers to *tube
    model::PiezoMaterialD material;
    bool isotropic = false;
    model::ModalOptions options;
  };

  FePhysics(Transducer transducer, const model::ModalPortModel& port, const BenchCircuit& circuit,
            Channel2Response channel2, std::vector<std::pair<std::string, double>> truth,
            std::string description)
      : transducer_(std::move(transducer)), port_(port), circuit_(circuit), ss_(port, circuit),
        channel2_(std::move(channel2)), truth_(std::move(truth)), description_(std::move(description)) {
    ports_.emplace(key(factors_), port);
  }

  std::vector<double> respond(const drivers::sim::PiecewiseLinear& v1,
                              std::span<const double> times) override {
    std::vector<double> v2 = ss_.simulate(v1, times);
    // The catalogue's channel-2 effects without an element of their own.
    if (channel2_ && times.size() > 1)
      apply_channel2_response(v2, (times.back() - times.front()) / double(times.size() - 1), channel2_);
    return v2;
  }
  std::vector<std::pair<std::string, double>> truth() const override { return truth_; }
  std::string description() const override { return description_; }
  // Calibration standards (SIM:DUT): same fixture, another device at the terminals.
  std::string select_dut(const drivers::sim::DutSelection& d) override {
    BenchCircuit c = circuit_;
    c.dut = d;
    try {
      ss_ = DividerStateSpace(port_, c);
    } catch (const std::exception& e) {
      return e.what();
    }
    circuit_.dut = d;
    return {};
  }
  std::string set_constant_factors(const drivers::sim::ConstantFactors& f) override {
    if (f == factors_) return {};
    try {
      auto it = ports_.find(key(f));
      if (it == ports_.end()) it = ports_.emplace(key(f), solve_port(f)).first;
      ss_ = DividerStateSpace(it->second, circuit_);
      port_ = it->second;
      factors_ = f;
    } catch (const std::exception& e) {
      return std::string("the transducer's constants scaled by YE11 ") + std::to_string(f.y_e11) +
             ", epsT33 " + std::to_string(f.eps_t33) + ", d31 " + std::to_string(f.d31) + ": " +
             e.what();
    }
    return {};
  }

 private:
  using Key = std::array<double, 3>;
  static Key key(const drivers::sim::ConstantFactors& f) { return {f.y_e11, f.eps_t33, f.d31}; }

  model::ModalPortModel solve_port(const drivers::sim::ConstantFactors& f) {
    model::PiezoMaterialD d = transducer_.material;
    if (transducer_.isotropic) {
      model::IsotropicPiezoParams ip = model::isotropic_params(d);
      ip.y_e11 *= f.y_e11;
      ip.eps_t33 *= f.eps_t33;
      ip.d31 *= f.d31;
      d = model::to_d_form(ip);
    } else {
      d.s_e11 /= f.y_e11;
      d.s_e12 /= f.y_e11;
      d.eps_t33 *= f.eps_t33;
      d.d31 *= f.d31;
    }
    return transducer_.solver->port_model(model::to_e_form(d), transducer_.options);
  }

  Transducer transducer_;
  model::ModalPortModel port_;  // the current constants'
  BenchCircuit circuit_;
  DividerStateSpace ss_;
  Channel2Response channel2_;
  std::vector<std::pair<std::string, double>> truth_;
  std::string description_;
  drivers::sim::ConstantFactors factors_;
  std::map<Key, model::ModalPortModel> ports_;
};

}  // namespace

model::TubeGeometry true_geometry(const SimSpec& spec) {
  model::TubeGeometry g = spec.geometry;
  const double rel = spec.unmodelled.wall_thickness_rel;
  if (!std::isfinite(rel) || !(rel > -1.0))
    throw std::invalid_argument("SimSpec: unmodelled.wall_thickness_rel must be finite and > -1");
  if (rel != 0.0)
    g.outer_diameter_m =
        g.inner_diameter_m + (g.outer_diameter_m - g.inner_diameter_m) * (1.0 + rel);
  return g;
}

std::shared_ptr<drivers::sim::SimBench> make_sim_bench(const SimSpec& spec, double nominal_r1_ohm) {
  if (!(nominal_r1_ohm > 0)) throw std::invalid_argument("make_sim_bench: R1 must be positive");
  const auto& fx = spec.effects;
  const auto& un = spec.unmodelled;
  auto mat = model::resolve_material({spec.material, spec.isotropic, spec.set});
  model::TubeGeometry g = true_geometry(spec);
  g.density_kg_m3 = mat.density_kg_m3;
  g.validate();
  FePhysics::Transducer tr;
  tr.tube = std::make_unique<model::TubeModel>(g);
  tr.solver = std::make_unique<model::ModalSolver>(*tr.tube);
  tr.material = mat.d;
  tr.isotropic = spec.isotropic;
  model::ModalOptions& mo = tr.options;
  mo.n_modes = spec.modes;
  mo.end_mass_fraction = fx.mass_loading;  // end-face masses: M + f·ΔM (model/end_mass.hpp)
  mo.outer_surface_impedance = un.acoustic_impedance_pa_s_m;  // validated by port_model
  const auto e = model::to_e_form(mat.d);
  model::ModalPortModel port = tr.solver->port_model(e, mo);

  BenchCircuit c;
  c.r1_ohm = nominal_r1_ohm * (1.0 + fx.r1_tolerance);
  c.series_resistance_ohm = fx.series_resistance_ohm;
  c.parallel_capacitance_f = fx.parallel_capacitance_f;
  c.daq_input_resistance_ohm = fx.daq_input_resistance_ohm;
  c.dielectric_loss = fx.dielectric_loss;
  c.damping = spec.damping;
  c.extra_damping_ratio = fx.mechanical_damping;
  for (const auto& r : un.parasitic_branches)
    c.parasitic_branches.push_back(parasitic_branch(r, port.c_static));

  const auto iso = model::isotropic_params(mat.d);
  std::vector<std::pair<std::string, double>> truth = {
      {"YE11", iso.y_e11},
      {"nu12", iso.nu12},
      {"d31", iso.d31},
      {"epsT33_rel", iso.eps_t33 / model::kEps0},
      {"sE11", mat.d.s_e11},
      {"sE12", mat.d.s_e12},
      {"rayleigh_alpha", spec.damping.alpha},
      {"rayleigh_beta", spec.damping.beta},
      {"r1_true_ohm", c.r1_ohm},
      {"static_capacitance_f", port.c_static}};
  for (const auto& info : model::effect_catalogue())
    truth.emplace_back("effect_" + std::string(info.name), fx.*(info.field));
  // Issue 21's out-of-catalogue causes, only when present (absent ones leave
  // the /truth group as it was). Branch i > 0 has the suffix _<i+1>.
  std::string what;
  for (std::size_t i = 0; i < un.parasitic_branches.size(); ++i) {
    const auto& r = un.parasitic_branches[i];
    // (snprintf: GCC 12 -O3 warns falsely (-Wrestrict) on "_" + std::to_string)
    char sfx_buf[24] = "";
    if (i > 0) std::snprintf(sfx_buf, sizeof sfx_buf, "_%zu", i + 1);
    const std::string sfx = sfx_buf;
    truth.emplace_back("unmodelled_parasitic_f_hz" + sfx, r.f_hz);
    truth.emplace_back("unmodelled_parasitic_k_eff" + sfx, r.k_eff);
    truth.emplace_back("unmodelled_parasitic_q" + sfx, r.q);
    what += ", parasitic branch at " + std::to_string(r.f_hz) + " Hz";
  }
  if (un.acoustic_impedance_pa_s_m != 0) {
    truth.emplace_back("unmodelled_acoustic_impedance", un.acoustic_impedance_pa_s_m);
    what += ", acoustic load " + std::to_string(un.acoustic_impedance_pa_s_m) + " Pa·s/m";
  }
  if (un.wall_thickness_rel != 0) {
    truth.emplace_back("unmodelled_wall_thickness_rel", un.wall_thickness_rel);
    what += ", wall thickness " + std::to_string(100.0 * un.wall_thickness_rel) + " %";
  }

  drivers::sim::DaqImperfections imp;
  imp.channel_skew_s = fx.channel_skew_s;
  imp.channel_gain = fx.channel_gain;
  imp.noise_rel[0] = imp.noise_rel[1] = spec.noise_rel;
  imp.noise_v[0] = imp.noise_v[1] = spec.noise_v;
  imp.adc_bits = spec.adc_bits;
  auto physics = std::make_unique<FePhysics>(
      std::move(tr), port, c, channel2_response(fx), std::move(truth),
      "FE tube " + mat.description + ", " + std::to_string(static_cast<int>(port.modes.size())) +
          " modes" + what);
  return std::make_shared<drivers::sim::SimBench>(std::move(physics), imp, spec.seed, spec.faults,
                                                  spec.disturbances);
}

}  // namespace piezo::acq
