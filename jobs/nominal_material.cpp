#include "jobs/nominal_material.hpp"

#include <stdexcept>

#include "model/material_presets.hpp"

namespace piezo::jobs {

NominalMaterial nominal_material(const std::string& cli, const std::optional<std::string>& capture_material) {
  constexpr const char* kDefault = "apc850";
  if (!cli.empty()) return {model::find_preset(cli).name, std::nullopt};
  const std::string text = capture_material.value_or("");
  if (text.empty())
    return {kDefault, std::string("the capture names no material (/setup/material): ") + kDefault +
                          " assumed; give --material to choose"};
  try {
    return {model::find_preset(text).name, std::nullopt};
  } catch (const std::invalid_argument&) {
  }
  const auto named = model::presets_named_in(text);
  if (!named.empty()) {
    std::string w = "the capture's material '" + text + "' is not a preset name; using '" + named.front() +
                    "' named in it";
    if (named.size() > 1) {
      w += " (it also names";
      for (std::size_t i = 1; i < named.size(); ++i) w += (i > 1 ? ", '" : " '") + named[i] + "'";
      w += ")";
    }
    return {named.front(), w + "; give --material to choose"};
  }
  return {kDefault, "the capture's material '" + text + "' names no preset; " + kDefault +
                        " assumed; give --material to choose"};
}

const std::vector<model::MaterialPreset>& material_presets() { return model::material_presets(); }

}  // namespace piezo::jobs
