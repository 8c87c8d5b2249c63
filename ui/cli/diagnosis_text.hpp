#pragma once
// The gap diagnosis as a terminal table (demo, update, replay).
#include <ostream>

#include "update/gap_diagnosis.hpp"

namespace piezo::cli {

void print_diagnosis(std::ostream& os, const update::GapDiagnosis& d);

}  // namespace piezo::cli
