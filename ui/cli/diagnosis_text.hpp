#pragma once
// The gap diagnosis as a terminal table (demo, update, replay).
#include <ostream>

#include "jobs/pipeline/pipeline.hpp"  // update::GapDiagnosis

namespace piezo::cli {

void print_diagnosis(std::ostream& os, const update::GapDiagnosis& d);

}  // namespace piezo::cli
