#pragma once
// "Did you mean": the nearest command or option name to a mistyped one, for
// CLI11's parse errors (ui/cli/main.cpp).
#include <CLI/CLI.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace piezo::cli {

// Optimal-string-alignment distance: insertions, deletions, substitutions and
// transpositions of neighbours each cost 1 ("replya" -> "replay": 1).
std::size_t edit_distance(std::string_view a, std::string_view b);

// The candidates nearest to `typed`: those at the smallest distance, if it is at
// most 2 and less than half the typed length, or else the one candidate that
// `typed` (3 characters or more) is a prefix of. Empty when nothing is near.
std::vector<std::string> nearest_names(std::string_view typed, const std::vector<std::string>& candidates);

// After a parse error of `app`: "did you mean ..." for the mistyped command or
// option names the error left unparsed, one line each; empty when none is near.
std::string did_you_mean(const CLI::App& app);

}  // namespace piezo::cli
