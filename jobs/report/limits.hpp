#pragma once
// Acceptance limits of a production lot (issue 19, item 4): a LIMITS.toml
// file of ranges on any quantity of a replay record, and the pass/fail of one
// capture against them with the reasons. Shared by `piezobench replay
// --limits`, the lot summary (lot_summary.hpp) and the GUI's pass/fail line,
// all of which hold the pipeline's result as the JSON of jobs::report_json().
//
// The file (docs/limits-example.toml is a commented example):
//
//   [lot]                        # optional
//   name = "APC850 tubes, lot 7"
//   bins = 20                    # histogram bins of the lot report (default: √n, 5..30)
//   outlier_z = 3.5              # modified z-score above which a value is an outlier
//
//   [[limit]]
//   quantity = "modes[0].fs_hz"  # a path into the record's "result" (below)
//   label = "fs, mode 1"         # optional, for the report (default: the path)
//   unit = "Hz"                  # optional
//   min = 49.0e3                 # min and/or max: a one- or two-sided range, bounds included
//   max = 53.0e3
//
//   [[limit]]
//   quantity = "diagnosis.verdict_effect"
//   allowed = ["none", "channel_skew"]   # the value must be one of these (strings or booleans)
//
// Paths address the record's "result" object (jobs/export/report_export's
// report_json), jq-style: keys joined by '.', array elements by a 0-based
// index in brackets — "modes[0]" is the first (lowest) mode, which the text
// table of `impedance --figures` numbers 1. Two conveniences: in an array of
// objects with a "name" field an element is addressed by its name
// ("parameters.YE11"), and an object with an "updated" number stands for that
// number (so "parameters.YE11" is the updated YE11; "parameters.YE11.original"
// and ".sigma" reach the rest). Which mode is modes[0] depends on how many the
// estimate found below it; to hold a limit to one mode whatever else was
// found, select it by frequency: "modes[fs_hz=45e3..55e3].k_eff" is the first
// mode whose fs lies in 45…55 kHz (no such mode: "not measured").
//
// Evaluation: a capture passes when every limit passes. A quantity that is
// absent, null (NaN) or of the wrong type is a FAIL with the reason "not
// measured" (never a silent pass); a capture whose replay failed is an ERROR
// (no result to judge), counted apart from pass and fail.
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace piezo::jobs::report {

// A malformed limits file; what() names the file, the line and the problem.
class LimitsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One bracket after a key: an index [i], or a selection [field=lo..hi] (the
// first element whose `field` is a number in [lo, hi]).
struct PathSelector {
  std::optional<std::size_t> index;
  std::string field;
  double lo = 0, hi = 0;
};

struct PathStep {
  std::string key;                      // object key, or an element's "name"; empty: brackets only
  std::vector<PathSelector> selectors;  // [i][j]… after the key
};

struct Limit {
  std::string quantity;  // the path as written
  std::vector<PathStep> path;
  std::string label, unit;  // label defaults to the path
  std::optional<double> min, max;
  std::vector<nlohmann::json> allowed;  // strings or booleans; empty: a numeric range
  int line = 0;                         // of its [[limit]] in the file
  bool numeric() const { return allowed.empty(); }
  bool two_sided() const { return min && max; }
};

struct Limits {
  std::string source;  // the file's path (or a name given to parse_limits)
  std::string name;    // [lot] name
  std::optional<int> bins;
  double outlier_z = 3.5;
  std::vector<Limit> limits;
};

// Throws LimitsError "SOURCE:LINE: problem" (or "SOURCE: problem" when no line applies).
Limits parse_limits(std::string_view toml_text, const std::string& source);
Limits read_limits(const std::filesystem::path& file);

// Throws std::invalid_argument for a path that does not parse ("modes[x]", "a..b").
std::vector<PathStep> parse_path(const std::string& path);
// The node a path leads to in `result`, after the conveniences above; nullptr when absent.
const nlohmann::json* resolve(const nlohmann::json& result, const std::vector<PathStep>& path);

struct LimitCheck {
  std::size_t limit = 0;  // index into Limits::limits
  // "pass" | "below min" | "above max" | "not allowed" | "not measured"
  std::string state;
  nlohmann::json value;  // what was found (null when not measured)
  std::string reason;  // empty when it passed, else e.g. "modes[0].fs_hz = 48712 Hz < min 49000 Hz"
  bool passed() const { return state == "pass"; }
};

struct CaptureVerdict {
  std::string status;                // "pass" | "fail" | "error"
  std::vector<LimitCheck> checks;    // one per limit (none for "error")
  std::vector<std::string> reasons;  // the failed checks' reasons, or the replay's error
};

LimitCheck check_limit(const Limits& l, std::size_t k, const nlohmann::json& result);
// `record`: a replay record ({"status", "result"} or {"status": "failed", "error"}).
CaptureVerdict evaluate_record(const Limits& l, const nlohmann::json& record);
// The same for a pipeline result alone (the GUI): status pass or fail.
CaptureVerdict evaluate_result(const Limits& l, const nlohmann::json& result);

// The record's "limits" object: {"file", "status", "reasons", "checks": [{quantity,
// state, value, min?, max?, allowed?}]}.
nlohmann::json verdict_json(const Limits& l, const CaptureVerdict& v);

}  // namespace piezo::jobs::report
