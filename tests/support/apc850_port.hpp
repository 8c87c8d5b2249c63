#pragma once
// The default tube's APC850 port model with 24 modes, built once per test program
// (shared by the tests that check a figure against the FE model's modal data).
#include "model/material_presets.hpp"
#include "model/modal.hpp"

namespace piezo::test {

inline const model::ModalPortModel& apc850_port() {
  static const model::ModalPortModel port = [] {
    model::TubeGeometry g;
    model::TubeModel tube(g);
    model::ModalSolver solver(tube);
    model::ModalOptions mo;
    mo.n_modes = 24;
    return solver.port_model(model::to_e_form(model::find_preset("apc850").material), mo);
  }();
  return port;
}

}  // namespace piezo::test
