#include "jobs/report/limits.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>

#include <toml++/toml.h>

namespace piezo::jobs::report {

namespace {

std::string at(const std::string& source, int line, const std::string& what) {
  return source + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + what;
}

int line_of(const toml::node& n) { return static_cast<int>(n.source().begin.line); }

std::string g6(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

std::string with_unit(double v, const std::string& unit) {
  return unit.empty() || unit == "-" ? g6(v) : g6(v) + " " + unit;
}

std::string shown(const nlohmann::json& v) {
  if (v.is_string()) return "\"" + v.get<std::string>() + "\"";
  return v.dump();
}

}  // namespace

std::vector<PathStep> parse_path(const std::string& path) {
  auto bad = [&](const std::string& why) {
    throw std::invalid_argument("quantity \"" + path + "\": " + why);
  };
  if (path.empty()) bad("empty path");
  std::vector<PathStep> out;
  std::size_t i = 0;
  while (i <= path.size()) {
    PathStep s;
    while (i < path.size() && path[i] != '.' && path[i] != '[') {
      const char c = path[i];
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-'))
        bad(std::string("unexpected character '") + c + "' (keys are letters, digits, _ and -)");
      s.key += c;
      ++i;
    }
    while (i < path.size() && path[i] == '[') {
      const std::size_t close = path.find(']', i);
      if (close == std::string::npos) bad("'[' without ']'");
      const std::string in = path.substr(i + 1, close - i - 1);
      PathSelector sel;
      const std::size_t eq = in.find('='), dots = in.find("..");
      auto number = [&](const std::string& t) {
        std::size_t used = 0;
        double x = 0;
        try {
          x = std::stod(t, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (t.empty() || used != t.size() || !std::isfinite(x))
          bad("\"" + t + "\" is not a number in [" + in + "]");
        return x;
      };
      if (eq != std::string::npos) {
        sel.field = in.substr(0, eq);
        if (sel.field.empty() || dots == std::string::npos || dots < eq)
          bad("a selection is [field=lo..hi], e.g. modes[fs_hz=45e3..55e3]");
        sel.lo = number(in.substr(eq + 1, dots - eq - 1));
        sel.hi = number(in.substr(dots + 2));
        if (sel.lo > sel.hi) bad("[" + in + "]: lo > hi");
      } else {
        if (in.empty() || !std::all_of(in.begin(), in.end(), [](char c) {
              return std::isdigit(static_cast<unsigned char>(c));
            }))
          bad("an index is a non-negative integer in brackets, e.g. modes[0], or a selection "
              "[field=lo..hi]");
        sel.index = std::stoul(in);
      }
      s.selectors.push_back(std::move(sel));
      i = close + 1;
    }
    if (s.key.empty() && (s.selectors.empty() || !out.empty())) bad("empty key");
    out.push_back(std::move(s));
    if (i == path.size()) break;
    if (path[i] != '.') bad(std::string("expected '.' or '[' before '") + path[i] + "'");
    ++i;
    if (i == path.size()) bad("ends with '.'");
  }
  return out;
}

namespace {
const nlohmann::json* resolve_in(const nlohmann::json& result, const std::vector<PathStep>& path,
                                 const nlohmann::json** parent);
}

const nlohmann::json* resolve(const nlohmann::json& result, const std::vector<PathStep>& path) {
  return resolve_in(result, path, nullptr);
}

namespace {
// As resolve, and the object that holds the node (its mode, its parameter).
const nlohmann::json* resolve_in(const nlohmann::json& result, const std::vector<PathStep>& path,
                                 const nlohmann::json** parent) {
  const nlohmann::json* n = &result;
  for (const auto& s : path) {
    if (parent && n->is_object()) *parent = n;
    if (!s.key.empty()) {
      if (n->is_object()) {
        const auto it = n->find(s.key);
        if (it == n->end()) return nullptr;
        n = &*it;
      } else if (n->is_array()) {  // an element by its "name"
        const nlohmann::json* hit = nullptr;
        for (const auto& e : *n)
          if (e.is_object() && e.contains("name") && e["name"].is_string() &&
              e["name"].get<std::string>() == s.key) {
            hit = &e;
            break;
          }
        if (!hit) return nullptr;
        n = hit;
      } else {
        return nullptr;
      }
    }
    for (const auto& sel : s.selectors) {
      if (!n->is_array()) return nullptr;
      if (sel.index) {
        if (*sel.index >= n->size()) return nullptr;
        n = &(*n)[*sel.index];
        continue;
      }
      const nlohmann::json* hit = nullptr;
      for (const auto& e : *n)
        if (e.is_object() && e.contains(sel.field) && e[sel.field].is_number()) {
          const double x = e[sel.field].get<double>();
          if (x >= sel.lo && x <= sel.hi) {
            hit = &e;
            break;
          }
        }
      if (!hit) return nullptr;
      n = hit;
    }
  }
  // A constant's object ({"updated": …, "status": …}) holds its number: the
  // holder is that object, whose status the limits read (a constant "not
  // identifiable" must never pass; it did, the holder was the result).
  if (n->is_object() && n->contains("updated") && (*n)["updated"].is_number()) {
    if (parent) *parent = n;
    n = &(*n)["updated"];
  }
  if (parent && n->is_object()) *parent = n;
  return n;
}
}  // namespace

Limits parse_limits(std::string_view text, const std::string& source) {
  toml::table t;
  try {
    t = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    throw LimitsError(
        at(source, static_cast<int>(e.source().begin.line), std::string(e.description())));
  }
  Limits L;
  L.source = source;
  for (auto&& [k, v] : t) {
    const std::string key(k.str());
    if (key == "lot") {
      const auto* lot = v.as_table();
      if (!lot) throw LimitsError(at(source, line_of(v), "lot: expected a table ([lot])"));
      for (auto&& [lk, lv] : *lot) {
        const std::string name(lk.str());
        const int ln = line_of(lv);
        if (name == "name") {
          if (!lv.is_string()) throw LimitsError(at(source, ln, "lot.name: expected a string"));
          L.name = *lv.value<std::string>();
        } else if (name == "bins") {
          const auto b = lv.value<std::int64_t>();
          if (!lv.is_integer() || !b || *b < 1 || *b > 200)
            throw LimitsError(at(source, ln, "lot.bins: expected an integer in 1..200"));
          L.bins = static_cast<int>(*b);
        } else if (name == "outlier_z") {
          const auto z = lv.value<double>();
          if (!z || !(*z > 0))
            throw LimitsError(at(source, ln, "lot.outlier_z: expected a number > 0"));
          L.outlier_z = *z;
        } else {
          throw LimitsError(
              at(source, ln, "lot." + name + ": unknown key (name, bins, outlier_z)"));
        }
      }
    } else if (key == "limit") {
      const auto* arr = v.as_array();
      if (!arr || !arr->is_array_of_tables())
        throw LimitsError(at(source, line_of(v), "limit: expected [[limit]] tables"));
      for (const auto& e : *arr) {
        const auto& tb = *e.as_table();
        Limit lim;
        lim.line = line_of(tb);
        bool has_allowed = false;
        for (auto&& [lk, lv] : tb) {
          const std::string name(lk.str());
          const int ln = line_of(lv);
          auto number = [&]() {
            const auto x = lv.value<double>();
            if (!(lv.is_number()) || !x || !std::isfinite(*x))
              throw LimitsError(at(source, ln, name + ": expected a finite number"));
            return *x;
          };
          auto str = [&]() {
            if (!lv.is_string()) throw LimitsError(at(source, ln, name + ": expected a string"));
            return *lv.value<std::string>();
          };
          if (name == "quantity") {
            lim.quantity = str();
            try {
              lim.path = parse_path(lim.quantity);
            } catch (const std::invalid_argument& x) {
              throw LimitsError(at(source, ln, x.what()));
            }
          } else if (name == "label") {
            lim.label = str();
          } else if (name == "unit") {
            lim.unit = str();
          } else if (name == "min") {
            lim.min = number();
          } else if (name == "max") {
            lim.max = number();
          } else if (name == "allowed") {
            has_allowed = true;
            const auto* a = lv.as_array();
            if (!a || a->empty())
              throw LimitsError(at(source, ln, "allowed: expected a non-empty array"));
            for (const auto& x : *a) {
              if (x.is_string())
                lim.allowed.emplace_back(*x.value<std::string>());
              else if (x.is_boolean())
                lim.allowed.emplace_back(*x.value<bool>());
              else
                throw LimitsError(
                    at(source, line_of(x) ? line_of(x) : ln, "allowed: strings or booleans only"));
            }
          } else {
            throw LimitsError(
                at(source, ln,
                   name + ": unknown key in [[limit]] (quantity, label, unit, min, max, allowed)"));
          }
        }
        if (lim.quantity.empty())
          throw LimitsError(at(source, lim.line, "[[limit]] without a quantity"));
        if (has_allowed && (lim.min || lim.max))
          throw LimitsError(
              at(source, lim.line, lim.quantity + ": give either min/max or allowed, not both"));
        if (!has_allowed && !lim.min && !lim.max)
          throw LimitsError(
              at(source, lim.line, lim.quantity + ": no limit (give min, max or allowed)"));
        if (lim.min && lim.max && *lim.min > *lim.max)
          throw LimitsError(at(source, lim.line,
                               lim.quantity + ": min " + g6(*lim.min) + " > max " + g6(*lim.max)));
        if (lim.label.empty()) lim.label = lim.quantity;
        L.limits.push_back(std::move(lim));
      }
    } else {
      throw LimitsError(at(source, line_of(v), key + ": unknown section (lot, limit)"));
    }
  }
  if (L.limits.empty()) throw LimitsError(at(source, 0, "no [[limit]] in the file"));
  return L;
}

Limits read_limits(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw LimitsError(file.string() + ": cannot open the limits file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw LimitsError(file.string() + ": cannot read the limits file");
  return parse_limits(text.str(), file.string());
}

namespace {
// A value outside what the quantity can physically be (issue 41 item 3): an
// estimate that says tan δ < 0, k ≤ 0, C ≤ 0 measured nothing, whatever the
// limit. By the path's last key, as the report's JSON names them.
std::optional<std::string> impossible(const std::string& key, double x) {
  auto has = [&](const char* s) { return key.find(s) != std::string::npos; };
  auto ends = [&](const char* s) {
    const std::string t(s);
    return key.size() >= t.size() && key.compare(key.size() - t.size(), t.size(), t) == 0;
  };
  if ((has("tan_delta") || key == "loss_tangent") && !ends("_sigma") && x < 0) return "tan delta below 0 is not physical";
  if ((key == "k_eff" || key == "k33" || key == "k31" || key == "kp" || key == "kt") && (x <= 0 || x >= 1))
    return "a coupling factor outside (0, 1) is not physical";
  if ((has("capacitance") || key == "c0_f" || key == "c1_f") && !ends("_sigma") && x <= 0)
    return "a capacitance at or below 0 is not physical";
  if ((key.rfind("qm", 0) == 0) && !ends("_sigma") && key != "qm_inverse" && x <= 0)
    return "a mechanical Q at or below 0 is not physical";
  if (ends("_hz") && x <= 0) return "a frequency at or below 0 is not physical";
  if ((key == "YE11" || key == "epsT33_rel") && x <= 0) return key + " at or below 0 is not physical";
  if (key == "nu12" && (x <= -1 || x >= 0.5)) return "nu12 outside (-1, 0.5) is not physical";
  return std::nullopt;
}
}  // namespace

LimitCheck check_limit(const Limits& L, std::size_t k, const nlohmann::json& result) {
  const Limit& lim = L.limits.at(k);
  LimitCheck c;
  c.limit = k;
  const nlohmann::json* holder = nullptr;
  const nlohmann::json* v = resolve_in(result, lim.path, &holder);
  // A figure its own status calls unreliable (or a constant not identifiable)
  // is not a measurement: it never passes a limit.
  if (v && holder && holder != v && holder->contains("status") && (*holder)["status"].is_string()) {
    const auto st = (*holder)["status"].get<std::string>();
    if (st == "unreliable" || st == "not identifiable" || st == "not_identifiable" || st == "non_physical") {
      c.state = "not measured";
      c.value = nullptr;
      c.reason = lim.quantity + " not measured: " + st;
      if (holder->contains("reasons") && (*holder)["reasons"].is_array() && !(*holder)["reasons"].empty() &&
          (*holder)["reasons"][0].is_string())
        c.reason += " (" + (*holder)["reasons"][0].get<std::string>() + ")";
      return c;
    }
  }
  const bool ok_type = v && (lim.numeric() ? v->is_number() : (v->is_string() || v->is_boolean()));
  if (!ok_type || (v->is_number() && !std::isfinite(v->get<double>()))) {
    c.state = "not measured";
    c.value = nullptr;
    c.reason = lim.quantity + " not measured" +
               (v && !v->is_null() ? " (found " + std::string(v->type_name()) + ", expected " +
                                         (lim.numeric() ? "a number" : "a string or boolean") + ")"
                                   : "");
    return c;
  }
  if (v->is_number() && !lim.path.empty()) {
    // The quantity's own name: the last key (parameters.YE11 → YE11, its "updated").
    std::string key = lim.path.back().key;
    if (const auto why = impossible(key, v->get<double>())) {
      c.state = "not measured";
      c.value = nullptr;
      c.reason = lim.quantity + " not measured: " + shown(*v) + " (" + *why + ")";
      return c;
    }
  }
  c.value = *v;
  if (!lim.numeric()) {
    if (std::find(lim.allowed.begin(), lim.allowed.end(), *v) != lim.allowed.end()) {
      c.state = "pass";
    } else {
      c.state = "not allowed";
      std::string list;
      for (const auto& a : lim.allowed) list += (list.empty() ? "" : ", ") + shown(a);
      c.reason = lim.quantity + " = " + shown(*v) + " not in the allowed list [" + list + "]";
    }
    return c;
  }
  const double x = v->get<double>();
  if (lim.min && x < *lim.min) {
    c.state = "below min";
    c.reason =
        lim.quantity + " = " + with_unit(x, lim.unit) + " < min " + with_unit(*lim.min, lim.unit);
  } else if (lim.max && x > *lim.max) {
    c.state = "above max";
    c.reason =
        lim.quantity + " = " + with_unit(x, lim.unit) + " > max " + with_unit(*lim.max, lim.unit);
  } else {
    c.state = "pass";
  }
  return c;
}

CaptureVerdict evaluate_result(const Limits& L, const nlohmann::json& result) {
  CaptureVerdict v;
  v.status = "pass";
  for (std::size_t k = 0; k < L.limits.size(); ++k) {
    v.checks.push_back(check_limit(L, k, result));
    if (!v.checks.back().passed()) {
      v.status = "fail";
      v.reasons.push_back(v.checks.back().reason);
    }
  }
  return v;
}

CaptureVerdict evaluate_record(const Limits& L, const nlohmann::json& record) {
  if (record.value("status", std::string()) != "ok" || !record.contains("result") ||
      !record["result"].is_object()) {
    CaptureVerdict v;
    v.status = "error";
    std::string msg = "replay failed";
    if (record.contains("error") && record["error"].is_object())
      msg += ": " + record["error"].value("message", std::string("(no message)"));
    v.reasons.push_back(msg);
    return v;
  }
  return evaluate_result(L, record["result"]);
}

nlohmann::json verdict_json(const Limits& L, const CaptureVerdict& v) {
  nlohmann::json j = {{"file", L.source}, {"status", v.status}, {"reasons", v.reasons}};
  j["checks"] = nlohmann::json::array();
  for (const auto& c : v.checks) {
    const auto& lim = L.limits[c.limit];
    nlohmann::json cj = {{"quantity", lim.quantity}, {"state", c.state}, {"value", c.value}};
    if (lim.min) cj["min"] = *lim.min;
    if (lim.max) cj["max"] = *lim.max;
    if (!lim.allowed.empty()) cj["allowed"] = lim.allowed;
    j["checks"].push_back(std::move(cj));
  }
  return j;
}

}  // namespace piezo::jobs::report
