#pragma once
// Test support: the true impedance of the simulated transducer (the FE port
// model of acquisition/sim_setup.cpp, with its dielectric loss, without any
// fixture), for checking compensated estimates against. Built the same way
// make_sim_bench builds the bench's tube; tests only (estimators never see it).
#include <complex>
#include <functional>
#include <memory>

#include "acquisition/divider_state_space.hpp"
#include "acquisition/sim_setup.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"

namespace piezo::test {

// Z(f) of the bare transducer of `spec` (its fixture effects ignored).
inline std::function<std::complex<double>(double)> true_tube_impedance(const acq::SimSpec& spec) {
  auto mat = model::resolve_material({spec.material, spec.isotropic, spec.set});
  model::TubeGeometry g = spec.geometry;
  g.density_kg_m3 = mat.density_kg_m3;
  model::TubeModel tube(g);
  model::ModalSolver solver(tube);
  model::ModalOptions mo;
  mo.n_modes = spec.modes;
  const auto port = solver.port_model(model::to_e_form(mat.d), mo);
  acq::BenchCircuit c;  // ideal divider: only R1 (its value cancels below)
  c.dielectric_loss = spec.effects.dielectric_loss;
  c.damping = spec.damping;
  c.extra_beta_s = spec.effects.mechanical_damping;
  auto ss = std::make_shared<acq::DividerStateSpace>(port, c);
  const double r1 = c.r1_ohm;
  return [ss, r1](double f) {
    const std::complex<double> t = ss->transfer(2 * M_PI * f);
    return r1 * t / (1.0 - t);
  };
}

}  // namespace piezo::test
