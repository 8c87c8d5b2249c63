#pragma once
// The jobs' room (jobs/): the nominal material of a capture's model (issue 18, item 4). The format
// calls /setup/material "name of the nominal material"; other tools write a
// description there ("PZT-5A class (APC850) radially poled tube"). Such a
// capture is never refused for it:
//   --material (the user's choice) wins, and must be a preset;
//   else the capture's string when it is a preset name;
//   else a preset named inside it (the first in material_presets() order when
//   it names several), with a warning;
//   else apc850 (the seed's material), with a warning that names --material.
#include <optional>
#include <string>
#include <vector>

#include "model/material_presets.hpp"

namespace piezo::jobs {

struct NominalMaterial {
  std::string name;                    // a preset name
  std::optional<std::string> warning;  // how it was chosen, when it was a guess
};

// Throws std::invalid_argument (listing the presets) when `cli` is given and unknown.
NominalMaterial nominal_material(const std::string& cli, const std::optional<std::string>& capture_material);

// The presets a nominal model starts from, in their order (model/material_presets.hpp):
// the GUI's material list, `model materials`.
const std::vector<model::MaterialPreset>& material_presets();

}  // namespace piezo::jobs
