#pragma once
// The jobs' room (jobs/): the error a job throws when its request is wrong
// (a bad option value, a file that is not what it should be). Front ends map
// it to their "bad input" answer — the CLI's exit code 2 (ui/cli/cli_common.hpp
// names it cli::InputError) — unlike a failure of the work itself.
#include <stdexcept>

namespace piezo::jobs {

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace piezo::jobs
