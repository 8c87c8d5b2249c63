#pragma once
// Process-wide counters of the FE model's expensive work (issue 43): the
// pipeline reads them before and after each stage (jobs/pipeline/work.hpp), a
// replay worker per capture, and the tests assert the counts of a replayed
// capture, so that a change that doubles the work fails CI without a timing
// assertion. Relaxed atomics: helper threads (the output-error fit's second
// FE solver) count into the same totals; forked replay workers have their own.
#include <atomic>

namespace piezo::model {

// ModalSolver::solve calls: one shifted factorisation and one Lanczos
// eigensolution each (a port model is one short- and one open-circuit solve).
inline std::atomic<long> g_modal_solves{0};

inline long modal_solves() { return g_modal_solves.load(std::memory_order_relaxed); }

// Of those, the ones not solved: a port model another capture of the same
// tube had solved, taken from the memo (model/port_memo.hpp). They count in
// g_modal_solves as the capture's own work (its counts do not depend on what
// the worker replayed before it); the work actually done is the difference.
inline std::atomic<long> g_modal_solves_remembered{0};

inline long modal_solves_remembered() { return g_modal_solves_remembered.load(std::memory_order_relaxed); }

// ReducedPort::port_model calls (model/reduced_port.hpp): a port model from a
// reduced basis, a small dense eigenproblem in place of a modal solve.
inline std::atomic<long> g_reduced_port_models{0};

inline long reduced_port_models() { return g_reduced_port_models.load(std::memory_order_relaxed); }

}  // namespace piezo::model
