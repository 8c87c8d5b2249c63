#pragma once
// A material as the CLI, plan files and the simulated bench name it: a preset,
// optionally reduced to the seed's isotropic class (§6.4.3), with overrides
// "KEY=VALUE,KEY=VALUE". Keys: YE11, nu12, d31, epsT33[_rel], rho (both
// classes); sE11, sE12, sE13, sE33, sE44, d33, d15, epsT11[_rel] (full class).
#include <string>

#include "model/material.hpp"

namespace piezo::model {

struct MaterialSpec {
  std::string preset = "apc850";
  bool isotropic = false;
  std::string set;  // overrides
};

struct ResolvedMaterial {
  PiezoMaterialD d;
  double density_kg_m3 = 0;
  std::string description;
};

// Throws std::invalid_argument naming the key and the problem.
ResolvedMaterial resolve_material(const MaterialSpec& spec);

}  // namespace piezo::model
