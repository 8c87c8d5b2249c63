#pragma once
// Test support: the true impedance of the simulated transducer (the FE port
// model of acquisition/sim_setup.cpp, with its dielectric loss, without any
// fixture), for checking compensated estimates against. Built the same way
// make_sim_bench builds the bench's tube; tests only (estimators never see it).
#include <complex>
#include <functional>
#include <memory>
#include <vector>

#include "acquisition/divider_state_space.hpp"
#include "acquisition/sim_setup.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"

namespace piezo::test {

inline model::ModalPortModel sim_port(const acq::SimSpec& spec) {
  auto mat = model::resolve_material({spec.material, spec.isotropic, spec.set});
  model::TubeGeometry g = acq::true_geometry(spec);  // with the unmodelled wall error, if any
  g.density_kg_m3 = mat.density_kg_m3;
  model::TubeModel tube(g);
  model::ModalSolver solver(tube);
  model::ModalOptions mo;
  mo.n_modes = spec.modes;
  mo.outer_surface_impedance = spec.unmodelled.acoustic_impedance_pa_s_m;
  return solver.port_model(model::to_e_form(mat.d), mo);
}

// The unmodelled parasitic branches of `spec` as element values (as make_sim_bench sets them).
inline std::vector<acq::ParasiticBranch> sim_parasitic_branches(const acq::SimSpec& spec,
                                                                const model::ModalPortModel& port) {
  std::vector<acq::ParasiticBranch> b;
  for (const auto& r : spec.unmodelled.parasitic_branches)
    b.push_back(acq::parasitic_branch(r, port.c_static));
  return b;
}

// Z(f) of the bare transducer of `spec` (its fixture effects ignored).
inline std::function<std::complex<double>(double)> true_tube_impedance(const acq::SimSpec& spec) {
  acq::BenchCircuit c;  // ideal divider: only R1 (its value cancels below)
  c.dielectric_loss = spec.effects.dielectric_loss;
  c.damping = spec.damping;
  c.extra_damping_ratio = spec.effects.mechanical_damping;
  const auto port = sim_port(spec);
  c.parasitic_branches = sim_parasitic_branches(spec, port);  // part of the transducer
  auto ss = std::make_shared<acq::DividerStateSpace>(port, c);
  const double r1 = c.r1_ohm;
  return [ss, r1](double f) {
    const std::complex<double> t = ss->transfer(2 * M_PI * f);
    return r1 * t / (1.0 - t);
  };
}

// What an ideal estimator measures on the simulated bench of `spec` with
// nominal R1: Z_m = R1_nom·T_m/(1 − T_m), T_m = (1 + g)·e^{−jωτ}·V2/V1 of the
// bench with every fixture effect (lead R, fixture C, DAQ input, R1 error,
// channel gain and skew) — free of any estimator's error.
inline std::function<std::complex<double>(double)> exact_measured_impedance(
    const acq::SimSpec& spec, double r1_nominal) {
  const auto& e = spec.effects;
  acq::BenchCircuit c;
  c.r1_ohm = r1_nominal * (1.0 + e.r1_tolerance);
  c.series_resistance_ohm = e.series_resistance_ohm;
  c.parallel_capacitance_f = e.parallel_capacitance_f;
  c.daq_input_resistance_ohm = e.daq_input_resistance_ohm;
  c.dielectric_loss = e.dielectric_loss;
  c.damping = spec.damping;
  c.extra_damping_ratio = e.mechanical_damping;
  const auto port = sim_port(spec);
  c.parasitic_branches = sim_parasitic_branches(spec, port);
  auto ss = std::make_shared<acq::DividerStateSpace>(port, c);
  const double g = e.channel_gain, tau = e.channel_skew_s;
  return [ss, g, tau, r1_nominal](double f) {
    const double w = 2 * M_PI * f;
    const std::complex<double> t =
        (1.0 + g) * std::exp(std::complex<double>(0, -w * tau)) * ss->transfer(w);
    return r1_nominal * t / (1.0 - t);
  };
}

}  // namespace piezo::test
