#pragma once
// Independent tasks of the output-error fit (the later starts, the scanned
// effects, the regrid under a lack of fit) on up to Problem::threads()
// threads: the fit's Problem and a fork of it on the second solver.
// Internal to update/output_error/.
#include <cstddef>
#include <functional>
#include <vector>

#include "update/output_error/fitter.hpp"
#include "update/output_error/forward_model.hpp"

namespace piezo::update::oe {

using Task = std::function<void(Problem&, Fitter&, std::size_t)>;

// Runs task(problem, fitter, order[k]) for every k. Each task starts from
// `start` (Problem::State), so its answer does not depend on the thread or
// the order; `order` lists the longest first. The fitter's Problem is left
// as the tasks found it (`start`); a task's exception is rethrown after all
// have run. Returns the FE models the fork built (fitter.prob counts its own).
int in_parallel(Fitter& fitter, const std::vector<std::size_t>& order, const Problem::State& start,
                const Task& task);

}  // namespace piezo::update::oe
