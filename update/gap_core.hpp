#pragma once
// The diagnosis core (issue 42 item 2): what the two gap diagnoses decide
// alike, whatever their residual. The impedance path (gap_diagnosis.cpp:
// ln Z(f) of repeated shots against the FE model) and the output-error path
// (gap_output_error.cpp: one or two shots' samples) each compute only the
// evidence their residual gives — per candidate effect its fit with the
// effect, Δχ², significance, whether it leaves a lack of fit, its held-out
// prediction — and call this core for
//   - the excess gap g = √max(0, χ²/ν − 1) and the held-out shrink
//     1 − g_after/g_before (both paths' numbers);
//   - the held-out check and the choice of the verdict's effect
//     (`choose_effect`: one rule, below);
//   - the verdict's fields and sentences shared by both (the named effect and
//     its twins, the aliases with how to separate them);
//   - where the misfit lies: update/gap_regions.hpp (located_gap_regions,
//     located_sentence), which both paths already call.
//
// The rule (`choose_effect`), for candidates in the path's order of preference:
//   - without a held-out prediction, a candidate is chosen if it explains the
//     fit data (significant, and — where the path tests it — no lack of fit
//     left with it);
//   - held-out data showing a gap: an explaining candidate must shrink that gap
//     by at least `min_shrink`; one that leaves some misfit, or one below the
//     fit's own significance ("weak"), by `dominant_shrink`;
//   - held-out data showing none: the candidate must explain the fit and keep
//     the held-out data within their noise (the path's own test of that);
//   - the first candidate that passes is the verdict; with `first_only`, only
//     the first is tried.
// The paths differ in what they pass, not in the rule: the impedance path
// adds effects greedily, one round at a time, offering the round's best
// candidate only (ranked by held-out χ² with it), if significant; the
// output-error path offers its significant candidates by Δχ², then its weak
// ones where the held-out data show a gap.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "update/gap_diagnosis.hpp"

namespace piezo::update::gap_core {

// g = √max(0, χ²/ν − 1): the misfit the noise does not explain.
double excess(double chi2_per_dof);

// 1 − g_after/g_before; none where there is no excess before.
std::optional<double> shrink(double chi2_per_dof_before, double chi2_per_dof_after);

// One candidate's evidence, in the path's terms.
struct CandidateEvidence {
  std::string name;
  bool significant = false;  // beyond the fit's significance (Δχ², at a physical value)
  bool explains = false;     // significant and, where the path tests it, no lack of fit left with it
  // Held-out, where the candidate was predicted on the held-out data:
  bool heldout_predicted = false;
  double heldout_shrink = 0;           // used where the held-out data show a gap
  bool heldout_within_noise = false;   // used where they show none
};

struct ChoiceRule {
  bool heldout = false;       // held-out data are there
  bool heldout_gap = false;   // … and show a gap of their own
  double min_shrink = 0.3;    // an explaining candidate's held-out shrink
  double dominant_shrink = 0.7;  // a candidate that leaves misfit, or a weak one
  bool first_only = false;
};

struct Choice {
  std::optional<std::size_t> chosen;  // index into the candidates
  bool partial = false;  // chosen although it leaves some misfit in the fit (held-out shrink ≥ dominant)
  bool weak = false;     // chosen below the fit's significance (held-out shrink ≥ dominant)
  // Significant candidates tried before the chosen one (or all, if none was)
  // that were predicted but failed the held-out check: "does not carry over".
  std::vector<std::size_t> failed_heldout;
};

Choice choose_effect(const std::vector<CandidateEvidence>& candidates, const ChoiceRule& rule);

// The verdict names `step` (one of d.effects or the greedy steps): its fields
// verdict_effect, verdict_alternatives and the twins' sentence. `data` is how
// the sentence calls the data ("This data", "This capture").
std::string twins_sentence(const std::vector<std::string>& twins, std::string_view data);

// " Not separable from the constants by <by> (aliases): a, b - <advice>." or "".
std::string alias_sentence(const std::vector<std::string>& aliases, std::string_view by);

// The aliased candidates of a diagnosis' effect table, in its order.
std::vector<std::string> alias_names(const std::vector<EffectReport>& effects);

}  // namespace piezo::update::gap_core
