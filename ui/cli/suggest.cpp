#include "ui/cli/suggest.hpp"

#include <algorithm>
#include <numeric>

namespace piezo::cli {

std::size_t edit_distance(std::string_view a, std::string_view b) {
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i)
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[n][m];
}

std::vector<std::string> nearest_names(std::string_view typed, const std::vector<std::string>& candidates) {
  // Compare the names without their dashes: "--jbos" is one edit from "--jobs".
  auto bare = [](std::string_view s) {
    while (!s.empty() && s.front() == '-') s.remove_prefix(1);
    return s;
  };
  const std::string_view t = bare(typed);
  std::vector<std::string> best;
  std::size_t best_d = 3;
  for (const auto& c : candidates) {
    if (c == typed) continue;
    const std::size_t d = edit_distance(t, bare(c));
    if (d > 2 || 2 * d >= t.size()) continue;
    if (d < best_d) {
      best_d = d;
      best.clear();
    }
    if (d == best_d && std::find(best.begin(), best.end(), c) == best.end()) best.push_back(c);
  }
  if (!best.empty() || t.size() < 3) return best;
  for (const auto& c : candidates)
    if (c.size() > typed.size() && c.compare(0, typed.size(), typed) == 0) best.push_back(c);
  if (best.size() > 1) best.clear();  // an ambiguous prefix suggests nothing
  return best;
}

namespace {

// Every option name valid at `cmd`: its own and those of the commands above it
// (--json is accepted before the command name).
std::vector<std::string> option_names(const CLI::App* cmd) {
  std::vector<std::string> names;
  for (const CLI::App* c = cmd; c; c = c->get_parent())
    for (const CLI::Option* o : c->get_options()) {
      for (const auto& l : o->get_lnames()) names.push_back("--" + l);
      for (const auto& s : o->get_snames()) names.push_back("-" + s);
    }
  return names;
}

std::vector<std::string> command_names(const CLI::App* cmd) {
  std::vector<std::string> names;
  for (const CLI::App* s : cmd->get_subcommands([](const CLI::App*) { return true; }))
    if (!s->get_name().empty()) names.push_back(s->get_name());
  return names;
}

std::string join_or(const std::vector<std::string>& v) {
  std::string s;
  for (std::size_t k = 0; k < v.size(); ++k) s += (k ? (k + 1 == v.size() ? " or " : ", ") : "") + ("'" + v[k] + "'");
  return s;
}

}  // namespace

std::string did_you_mean(const CLI::App& app) {
  // The deepest command the parse reached: its leftovers are what went wrong.
  const CLI::App* cmd = &app;
  for (;;) {
    auto used = cmd->get_subcommands();
    if (used.empty()) break;
    cmd = used.back();
  }
  std::string out;
  bool command_tried = false;
  for (const CLI::App* c = cmd; c; c = c->get_parent())
    for (std::string token : c->remaining()) {
      if (token.rfind("-", 0) == 0) {
        if (const auto eq = token.find('='); eq != std::string::npos) token.resize(eq);
        const auto near = nearest_names(token, option_names(cmd));
        if (!near.empty()) out += "piezobench: " + token + ": did you mean " + join_or(near) + "?\n";
      } else if (!command_tried && cmd->get_subcommands().empty() && !command_names(cmd).empty()) {
        command_tried = true;  // the first word where a command was due
        const auto near = nearest_names(token, command_names(cmd));
        if (!near.empty())
          out += "piezobench: '" + token + "' is not a command: did you mean " + join_or(near) + "?\n";
      }
    }
  return out;
}

}  // namespace piezo::cli
