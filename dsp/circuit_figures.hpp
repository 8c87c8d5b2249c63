#pragma once
// The per-mode figures of an equivalent circuit (dsp/equivalent_circuit.hpp):
// fs, the lossless network's parallel resonances fp (Foster; a weak "guest"
// branch inside a strong one's fs–fp has none), fm/fn, fr/fa, both k_eff
// forms, Qm two ways and each mode's window. The fit's σ propagation uses the
// vector forms below.
#include <vector>

#include "dsp/equivalent_circuit.hpp"

namespace piezo::dsp {

// Figures of every branch, ascending fs (values only).
std::vector<CircuitModeFigures> all_circuit_figures(const EquivalentCircuit& c);
// Every figure of every mode in one vector (named_figures' order), and the slots to write σ back.
std::vector<double> circuit_figure_vector(const std::vector<CircuitModeFigures>& ms);
std::vector<Figure*> circuit_figure_slots(std::vector<CircuitModeFigures>& ms);

}  // namespace piezo::dsp
