#pragma once
// The gap diagnosis as a terminal table (demo, update, replay).
#include <ostream>

#include "jobs/pipeline/pipeline.hpp"  // update::GapDiagnosis

namespace piezo::cli {

void print_diagnosis(std::ostream& os, const update::GapDiagnosis& d);

// The constants refitted with the effect the diagnosis named (the result),
// beside the update's own without it; nothing when no effect was named.
void print_corrected(std::ostream& os, const jobs::PipelineResult& r);

}  // namespace piezo::cli
