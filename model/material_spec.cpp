#include "model/material_spec.hpp"

#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <vector>

#include "model/material_presets.hpp"

namespace piezo::model {

namespace {
std::vector<std::pair<std::string, double>> parse_assignments(const std::string& set) {
  std::vector<std::pair<std::string, double>> out;
  std::size_t pos = 0;
  while (pos < set.size()) {
    std::size_t comma = set.find(',', pos);
    std::string item = set.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    pos = comma == std::string::npos ? set.size() : comma + 1;
    if (item.empty()) continue;
    auto eq = item.find('=');
    if (eq == std::string::npos)
      throw std::invalid_argument("material override '" + item + "': expected KEY=VALUE");
    std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    char* end = nullptr;
    double v = std::strtod(value.c_str(), &end);
    if (value.empty() || *end != '\0' || !std::isfinite(v))
      throw std::invalid_argument("material override '" + key + "': '" + value + "' is not a number");
    out.emplace_back(key, v);
  }
  return out;
}
}  // namespace

ResolvedMaterial resolve_material(const MaterialSpec& spec) {
  const MaterialPreset& p = find_preset(spec.preset);
  ResolvedMaterial r;
  r.density_kg_m3 = p.density_kg_m3;
  r.description = p.name + (spec.isotropic ? " (isotropic class)" : "");
  auto overrides = parse_assignments(spec.set);
  std::erase_if(overrides, [&](const auto& kv) {
    if (kv.first != "rho") return false;
    if (!(kv.second > 0)) throw std::invalid_argument("material override 'rho': must be positive");
    r.density_kg_m3 = kv.second;
    return true;
  });
  if (spec.isotropic) {
    IsotropicPiezoParams ip = isotropic_params(p.material);
    for (const auto& [k, v] : overrides) {
      if (k == "YE11") ip.y_e11 = v;
      else if (k == "nu12") ip.nu12 = v;
      else if (k == "d31") ip.d31 = v;
      else if (k == "epsT33_rel") ip.eps_t33 = v * kEps0;
      else if (k == "epsT33") ip.eps_t33 = v;
      else
        throw std::invalid_argument("material override '" + k +
                                    "' is not a parameter of the isotropic class (YE11, nu12, d31, "
                                    "epsT33_rel, rho)");
    }
    if (!(ip.y_e11 > 0) || !(ip.nu12 > -1 && ip.nu12 < 0.5) || !(ip.eps_t33 > 0))
      throw std::invalid_argument("material overrides: need YE11 > 0, -1 < nu12 < 0.5, epsT33 > 0");
    r.d = to_d_form(ip);
  } else {
    PiezoMaterialD d = p.material;
    for (const auto& [k, v] : overrides) {
      if (k == "sE11") d.s_e11 = v;
      else if (k == "sE12") d.s_e12 = v;
      else if (k == "sE13") d.s_e13 = v;
      else if (k == "sE33") d.s_e33 = v;
      else if (k == "sE44") d.s_e44 = v;
      else if (k == "d31") d.d31 = v;
      else if (k == "d33") d.d33 = v;
      else if (k == "d15") d.d15 = v;
      else if (k == "epsT11_rel") d.eps_t11 = v * kEps0;
      else if (k == "epsT33_rel") d.eps_t33 = v * kEps0;
      else if (k == "epsT11") d.eps_t11 = v;
      else if (k == "epsT33") d.eps_t33 = v;
      else if (k == "YE11" || k == "nu12") {
        // in-plane engineering constants: sE11 = 1/YE11, sE12 = −nu12/YE11
        double y = 1.0 / d.s_e11, nu = -d.s_e12 / d.s_e11;
        (k == "YE11" ? y : nu) = v;
        d.s_e11 = 1.0 / y;
        d.s_e12 = -nu / y;
      } else {
        throw std::invalid_argument("material override '" + k +
                                    "': unknown d-form parameter (sE11 sE12 sE13 sE33 sE44 d31 d33 d15 "
                                    "epsT11[_rel] epsT33[_rel] YE11 nu12 rho)");
      }
    }
    r.d = d;
  }
  to_e_form(r.d);  // validates (throws on a non-physical material)
  return r;
}

}  // namespace piezo::model
