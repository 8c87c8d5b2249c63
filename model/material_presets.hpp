#pragma once
// Named piezoceramic presets in d-form (IEEE, 3 = poling), each with density and
// typical losses, sourced in material_presets.cpp.
#include <string>
#include <string_view>
#include <vector>

#include "model/material.hpp"

namespace piezo::model {

struct MaterialPreset {
  std::string name;         // lookup key, lower case ("apc850")
  std::string description;  // human-readable, with the source
  PiezoMaterialD material;
  double density_kg_m3 = 0;
  MaterialLosses losses;    // datasheet Qm and tanδ (not used unless asked for)
};

// All presets: apc850 (seed Table 2), pzt4, pzt8, pzt5h, pzt5a.
const std::vector<MaterialPreset>& material_presets();
// Case-insensitive; '-' and '_' ignored ("PZT-5H" == "pzt5h"). Throws
// std::invalid_argument listing the known names when not found.
const MaterialPreset& find_preset(std::string_view name);
// The presets whose name appears inside a free text ("PZT-5A class (APC850)
// radially poled tube" names pzt5a and apc850), matched as find_preset does
// (case, '-', '_' and blanks ignored), in the order of material_presets().
std::vector<std::string> presets_named_in(std::string_view text);

}  // namespace piezo::model
