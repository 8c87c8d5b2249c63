// The diagnosis core both gap paths call (update/gap_core): the excess gap
// and held-out shrink against their formulas, the choice of the verdict's
// effect case by case (each branch of the rule in gap_core.hpp), and the
// shared sentences' exact text (JSON and reports quote them).
#include "update/gap_core.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace piezo::update;

namespace {

gap_core::CandidateEvidence candidate(const char* name, bool significant, bool explains) {
  return {name, significant, explains};
}

gap_core::CandidateEvidence predicted(gap_core::CandidateEvidence c, double shrink, bool within_noise) {
  c.heldout_predicted = true;
  c.heldout_shrink = shrink;
  c.heldout_within_noise = within_noise;
  return c;
}

}  // namespace

TEST(GapCore, ExcessAndShrinkFollowTheirFormulas) {
  EXPECT_DOUBLE_EQ(gap_core::excess(5.0), 2.0);  // √(5 − 1)
  EXPECT_EQ(gap_core::excess(0.7), 0.0);         // below the noise: no excess
  EXPECT_DOUBLE_EQ(*gap_core::shrink(5.0, 2.0), 0.5);  // 1 − √1/√4
  EXPECT_DOUBLE_EQ(*gap_core::shrink(5.0, 0.9), 1.0);
  EXPECT_LT(*gap_core::shrink(2.0, 5.0), 0.0);  // an effect that makes it worse
  EXPECT_FALSE(gap_core::shrink(1.0, 3.0));     // nothing to shrink
}

TEST(GapCore, WithoutHeldOutDataTheFirstExplainingCandidateIsChosen) {
  const auto c = gap_core::choose_effect(
      {candidate("a", true, false), candidate("b", true, true), candidate("c", true, true)}, {});
  ASSERT_TRUE(c.chosen);
  EXPECT_EQ(*c.chosen, 1u);
  EXPECT_FALSE(c.partial);
  EXPECT_FALSE(c.weak);
  EXPECT_TRUE(c.failed_heldout.empty());
  EXPECT_FALSE(gap_core::choose_effect({candidate("a", true, false)}, {}).chosen);
}

TEST(GapCore, AHeldOutGapMustShrinkByTheRuleOfEachKindOfCandidate) {
  gap_core::ChoiceRule rule{.heldout = true, .heldout_gap = true, .min_shrink = 0.3, .dominant_shrink = 0.7};
  // An explaining candidate that does not carry over, then one that does.
  auto c = gap_core::choose_effect({predicted(candidate("a", true, true), 0.2, false),
                                    predicted(candidate("b", true, true), 0.4, false)}, rule);
  ASSERT_TRUE(c.chosen);
  EXPECT_EQ(*c.chosen, 1u);
  ASSERT_EQ(c.failed_heldout.size(), 1u);
  EXPECT_EQ(c.failed_heldout[0], 0u);
  // One that leaves misfit in the fit needs the dominant shrink: chosen as partial.
  c = gap_core::choose_effect({predicted(candidate("a", true, false), 0.5, false),
                               predicted(candidate("b", true, false), 0.8, false)}, rule);
  ASSERT_TRUE(c.chosen);
  EXPECT_EQ(*c.chosen, 1u);
  EXPECT_TRUE(c.partial);
  EXPECT_FALSE(c.weak);
  // A weak one (below the fit's significance) too; it is never listed as failed.
  c = gap_core::choose_effect({predicted(candidate("w", false, false), 0.5, false),
                               predicted(candidate("v", false, false), 0.75, false)}, rule);
  ASSERT_TRUE(c.chosen);
  EXPECT_EQ(*c.chosen, 1u);
  EXPECT_TRUE(c.weak);
  EXPECT_TRUE(c.failed_heldout.empty());
  // A shrink that is not a number never passes.
  EXPECT_FALSE(gap_core::choose_effect({predicted(candidate("a", true, true),
                                                  std::numeric_limits<double>::quiet_NaN(), false)}, rule).chosen);
  // A candidate without a held-out prediction is judged on the fit alone.
  c = gap_core::choose_effect({candidate("a", true, false), candidate("b", true, true)}, rule);
  ASSERT_TRUE(c.chosen);
  EXPECT_EQ(*c.chosen, 1u);
}

TEST(GapCore, HeldOutDataWithoutAGapMustStayWithinTheirNoise) {
  const gap_core::ChoiceRule rule{.heldout = true, .heldout_gap = false};
  auto c = gap_core::choose_effect({predicted(candidate("a", true, true), 0.0, false),
                                    predicted(candidate("b", true, false), 0.0, true),
                                    predicted(candidate("c", true, true), 0.0, true)}, rule);
  ASSERT_TRUE(c.chosen);
  EXPECT_EQ(*c.chosen, 2u);
  // "a" explains the fit but makes the held-out data worse: it does not carry
  // over; "b" leaves misfit and there is no held-out gap it could remove.
  ASSERT_EQ(c.failed_heldout.size(), 1u);
  EXPECT_EQ(c.failed_heldout[0], 0u);
}

TEST(GapCore, FirstOnlyTriesOneCandidate) {
  gap_core::ChoiceRule rule{.heldout = true, .heldout_gap = true, .first_only = true};
  const auto c = gap_core::choose_effect({predicted(candidate("a", true, true), 0.1, false),
                                          predicted(candidate("b", true, true), 0.9, false)}, rule);
  EXPECT_FALSE(c.chosen);
  EXPECT_EQ(c.failed_heldout.size(), 1u);
}

TEST(GapCore, SentencesKeepTheirWording) {
  EXPECT_EQ(gap_core::twins_sentence({}, "This data"), "");
  EXPECT_EQ(gap_core::twins_sentence({"channel_skew", "channel_gain"}, "This capture"),
            " This capture cannot tell it from channel_skew, channel_gain (same signature).");
  EXPECT_EQ(gap_core::alias_sentence({}, "this capture"), "");
  const std::string s = gap_core::alias_sentence({"r1_tolerance"}, "the impedance alone");
  EXPECT_EQ(s.rfind(" Not separable from the constants by the impedance alone (aliases): r1_tolerance - ", 0), 0u) << s;
  EXPECT_EQ(s.back(), '.');
  std::vector<EffectReport> effects(3);
  effects[0].name = "a";
  effects[1].name = "b";
  effects[1].alias = true;
  effects[2].name = "c";
  effects[2].alias = true;
  EXPECT_EQ(gap_core::alias_names(effects), (std::vector<std::string>{"b", "c"}));
}
