#pragma once
// A chance given by its log10 as people read it (it may lie far below what a
// double holds): "1e-12", "3.2e-05", "0.27"; below 1e-300 "< 1e-300"; NaN "—".
// In dsp/ so that every layer's messages print chances alike
// (jobs::format_probability_log10 is this).
#include <string>

namespace piezo::dsp {

std::string probability_text(double log10_p);

}  // namespace piezo::dsp
