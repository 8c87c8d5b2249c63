#pragma once
// The seed's lab circuit (chapter 5's measurement): the nominal series
// resistor R1 of the divider, the default of every plan, simulated bench and
// command that does not state its own (issue 42: it was written in 8 files).
namespace piezo::model {

inline constexpr double kSeedR1Ohm = 3140.0;

}  // namespace piezo::model
