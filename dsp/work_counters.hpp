#pragma once
// Process-wide counters of dsp/'s expensive work (issue 43; see
// model/work_counters.hpp): Prony-SS decompositions (one Hankel SVD each,
// at any order or replicate) and FFTs executed (RealFft, forward or inverse;
// a DecimatedInverse, one inverse DFT evaluated at every d-th sample by two
// shorter complex FFTs, counts as one).
#include <atomic>

namespace piezo::dsp {

inline std::atomic<long> g_prony_decompositions{0};
inline std::atomic<long> g_ffts{0};

inline long prony_decompositions() { return g_prony_decompositions.load(std::memory_order_relaxed); }
inline long ffts() { return g_ffts.load(std::memory_order_relaxed); }

}  // namespace piezo::dsp
