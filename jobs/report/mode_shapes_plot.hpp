#pragma once
// The tube's mode shapes drawn as the seed draws them (Figs 7, 12, 13): the
// r–z section's mesh, undeformed and deformed by each mode (node + s·φ, one
// scale per panel so that the largest displacement is a fixed share of the
// wall), one panel per mode — the electrically active symmetric modes in short
// and open circuit, and the first antisymmetric ones (the same in both
// circuits: they carry no charge). `model modal --plot-shapes`.
#include <filesystem>
#include <string>

#include "jobs/report/plot_spec.hpp"
#include "model/mesh.hpp"
#include "model/modal.hpp"

namespace piezo::jobs::report {

struct ModeShapesOptions {
  int symmetric = 3;       // active symmetric modes per circuit
  int antisymmetric = 3;   // antisymmetric modes (short circuit)
  double wall_share = 0.5; // the largest displacement drawn as this share of the wall thickness
};

Figure mode_shapes_figure(const model::TubeMesh& mesh, const model::ModalResult& short_circuit,
                          const model::ModalResult& open_circuit, const std::string& subtitle,
                          const ModeShapesOptions& opt = {});

}  // namespace piezo::jobs::report
