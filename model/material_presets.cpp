#include "model/material_presets.hpp"

#include <cctype>
#include <stdexcept>

namespace piezo::model {

namespace {

PiezoMaterialD d_form(double s11, double s12, double s13, double s33, double s44, double d31,
                      double d33, double d15, double epsr11, double epsr33) {
  PiezoMaterialD m;
  m.s_e11 = s11 * 1e-12;
  m.s_e12 = s12 * 1e-12;
  m.s_e13 = s13 * 1e-12;
  m.s_e33 = s33 * 1e-12;
  m.s_e44 = s44 * 1e-12;
  m.d31 = d31 * 1e-12;
  m.d33 = d33 * 1e-12;
  m.d15 = d15 * 1e-12;
  m.eps_t11 = epsr11 * kEps0;
  m.eps_t33 = epsr33 * kEps0;
  return m;
}

MaterialLosses losses(double qm, double tan_delta) {
  MaterialLosses l;
  l.qm = qm;
  l.tan_delta = tan_delta;
  return l;
}

std::vector<MaterialPreset> make_presets() {
  std::vector<MaterialPreset> v;
  // APC850 ("Navy II"): seed Table 2 (shared/reference/published-tube-results.json),
  // density 7600 kg/m³ as used by the seed's FE models. Qm = 80 and tanδ = 1.4 %
  // from APC International's "Physical and piezoelectric properties of APC
  // materials" datasheet (APC 850).
  v.push_back({"apc850", "APC 850 (Navy II), seed Table 2",
               d_form(15.8, -4.9, -5.74, 18.5, 46.0, -175, 400, 590, 1851, 1594), 7600.0,
               losses(80, 0.014)});
  // PZT-4, PZT-8, PZT-5H, PZT-5A (Navy I, III, VI, II): D. Berlincourt, H. Krueger,
  // C. Near, "Properties of Morgan Electro Ceramic ceramics", Morgan Electro
  // Ceramics Technical Publication TP-226 (the Vernitron/Morgan datasheet
  // values also reproduced in Sherman & Butler, "Transducers and Arrays for
  // Underwater Sound", 2007, Appendix A.5). sE66 = 2(sE11 − sE12) holds for
  // each set (checked in tests/model/test_material.cpp).
  v.push_back({"pzt4", "PZT-4 (Navy I), Berlincourt et al. TP-226",
               d_form(12.3, -4.05, -5.31, 15.5, 39.0, -123, 289, 496, 1475, 1300), 7500.0,
               losses(500, 0.004)});
  v.push_back({"pzt8", "PZT-8 (Navy III), Berlincourt et al. TP-226",
               d_form(11.5, -3.7, -4.8, 13.5, 31.9, -97, 225, 330, 1290, 1000), 7600.0,
               losses(1000, 0.004)});
  v.push_back({"pzt5h", "PZT-5H (Navy VI), Berlincourt et al. TP-226",
               d_form(16.5, -4.78, -8.45, 20.7, 43.5, -274, 593, 741, 3130, 3400), 7500.0,
               losses(65, 0.02)});
  v.push_back({"pzt5a", "PZT-5A (Navy II), Berlincourt et al. TP-226",
               d_form(16.4, -5.74, -7.22, 18.8, 47.5, -171, 374, 584, 1730, 1700), 7750.0,
               losses(75, 0.02)});
  return v;
}

std::string key(std::string_view s) {
  std::string k;
  for (char c : s)
    if (c != '-' && c != '_' && c != ' ')
      k.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  return k;
}

}  // namespace

const std::vector<MaterialPreset>& material_presets() {
  static const std::vector<MaterialPreset> presets = make_presets();
  return presets;
}

const MaterialPreset& find_preset(std::string_view name) {
  const std::string k = key(name);
  std::string known;
  for (const auto& p : material_presets()) {
    if (p.name == k) return p;
    known += (known.empty() ? "" : ", ") + p.name;
  }
  throw std::invalid_argument("find_preset: unknown material '" + std::string(name) +
                              "' (known: " + known + ")");
}

std::vector<std::string> presets_named_in(std::string_view text) {
  const std::string t = key(text);
  std::vector<std::string> out;
  for (const auto& p : material_presets())
    if (t.find(p.name) != std::string::npos) out.push_back(p.name);
  return out;
}

}  // namespace piezo::model
