#pragma once
#include <string>

#include "ui/cli/cli_common.hpp"
#include "jobs/update_capture_job.hpp"  // update::OeOptions

namespace piezo::cli {

// `piezobench update CAP.h5 --method oe|cmcm|lm|all` (see cmd_update_capture.cpp).
void run_update_capture(Context& ctx, const std::string& file, const std::string& method,
                        const std::string& material, bool isotropic, const update::OeOptions& oe = {});

}  // namespace piezo::cli
