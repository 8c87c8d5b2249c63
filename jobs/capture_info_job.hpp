#pragma once
// The jobs' room (jobs/): `piezobench capture info FILE` — a capture's set-up
// and, per shot, N, rate, excitation, min/max/RMS of v1 and v2 and a clipping
// flag (dsp/signal_stats.hpp), as JSON. ui/cli/cmd_capture.cpp prints it.
#include <nlohmann/json.hpp>
#include <string>

#include "acquisition/capture.hpp"

namespace piezo::jobs {

// Reads the capture in a child process (a crash of libhdf5 costs the file only).
nlohmann::json capture_info(const std::string& path);
nlohmann::json capture_info_json(const acq::Capture& cap);

}  // namespace piezo::jobs
