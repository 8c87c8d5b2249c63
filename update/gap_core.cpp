#include "update/gap_core.hpp"

#include <algorithm>
#include <cmath>

#include "model/effects.hpp"

namespace piezo::update::gap_core {

double excess(double chi2_per_dof) { return std::sqrt(std::max(0.0, chi2_per_dof - 1.0)); }

std::optional<double> shrink(double chi2_per_dof_before, double chi2_per_dof_after) {
  const double before = excess(chi2_per_dof_before);
  if (!(before > 0)) return std::nullopt;
  return 1.0 - excess(chi2_per_dof_after) / before;
}

Choice choose_effect(const std::vector<CandidateEvidence>& candidates, const ChoiceRule& rule) {
  Choice out;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const CandidateEvidence& c = candidates[i];
    bool ok = false, partial = false, weak = false;
    if (!rule.heldout || !c.heldout_predicted) {
      ok = c.explains;
    } else if (rule.heldout_gap) {
      // A NaN shrink (a held-out χ² that is not finite) never passes.
      ok = c.explains && c.significant ? c.heldout_shrink >= rule.min_shrink
                                       : c.heldout_shrink >= rule.dominant_shrink;
      partial = ok && !c.explains;
      weak = ok && !c.significant;
    } else {
      ok = c.explains && c.heldout_within_noise;
    }
    if (ok) {
      out.chosen = i;
      out.partial = partial;
      out.weak = weak;
      return out;
    }
    if (rule.heldout && c.heldout_predicted && (c.explains || rule.heldout_gap) && c.significant)
      out.failed_heldout.push_back(i);
    if (rule.first_only) break;
  }
  return out;
}

std::string twins_sentence(const std::vector<std::string>& twins, std::string_view data) {
  if (twins.empty()) return {};
  std::string s(" ");  // appended piece by piece: GCC 12's -Wrestrict misreads " " + std::string
  s.append(data).append(" cannot tell it from ");
  for (std::size_t i = 0; i < twins.size(); ++i) s.append(i ? ", " : "").append(twins[i]);
  return s.append(" (same signature).");
}

std::string alias_sentence(const std::vector<std::string>& aliases, std::string_view by) {
  if (aliases.empty()) return {};
  std::string s(" Not separable from the constants by ");
  s.append(by).append(" (aliases): ");
  for (std::size_t i = 0; i < aliases.size(); ++i) s.append(i ? ", " : "").append(aliases[i]);
  return s.append(" - ").append(model::separation_advice(aliases)).append(".");
}

std::vector<std::string> alias_names(const std::vector<EffectReport>& effects) {
  std::vector<std::string> out;
  for (const auto& e : effects)
    if (e.alias) out.push_back(e.name);
  return out;
}

}  // namespace piezo::update::gap_core
