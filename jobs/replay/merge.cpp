#include "jobs/replay/merge.hpp"

#include <fstream>
#include <map>
#include <set>
#include <stdexcept>

#include "acquisition/results_file.hpp"
#include "jobs/replay/replay_batch.hpp"
#include "jobs/replay/replay_record.hpp"
#include "jobs/json/json_text.hpp"

namespace piezo::jobs::replay {

namespace fs = std::filesystem;

namespace {

fs::path identity(const fs::path& p) {
  std::error_code ec;
  fs::path c = fs::weakly_canonical(p, ec);
  return ec ? fs::absolute(p).lexically_normal() : c;
}

}  // namespace

MergeSummary merge_results(const MergeOptions& opt) {
  if (opt.inputs.empty()) throw std::invalid_argument("replay-merge: no input results file given");
  if (opt.out.empty()) throw std::invalid_argument("replay-merge: --out ALL.h5 is required");
  for (const auto& in : opt.inputs)
    if (identity(in) == identity(opt.out))
      throw std::invalid_argument("replay-merge: --out " + opt.out.string() + " is also an input");
  std::error_code ec;
  if (fs::exists(opt.out, ec) && !opt.overwrite)
    throw std::invalid_argument("replay-merge: " + opt.out.string() +
                                " already exists (--overwrite replaces it)");

  // Which record comes from which input: decided from the indexes first, so
  // that a bad input refuses the merge before anything is written.
  struct Choice {
    std::size_t input;
    std::string status, path, sha256;
  };
  std::map<std::string, Choice> chosen;
  MergeSummary sum;
  for (std::size_t k = 0; k < opt.inputs.size(); ++k)
    acq::for_each_result(opt.inputs[k], [&](const acq::ResultRecord& r) {
      auto it = chosen.find(r.key);
      if (it == chosen.end()) {
        chosen.emplace(r.key, Choice{k, r.status, r.input_path, r.sha256});
        return;
      }
      ++sum.duplicates;
      if (it->second.status != "ok" && r.status == "ok")
        it->second = Choice{k, r.status, r.input_path, r.sha256};
    });
  std::map<std::string, std::set<std::string>> digests;  // path → digests
  for (const auto& [key, c] : chosen) digests[c.path].insert(c.sha256);
  for (const auto& [path, d] : digests)
    if (d.size() > 1)
      sum.warnings.push_back(
          path + ": " + std::to_string(d.size()) +
          " records with different SHA-256 (the file changed between runs); all kept");

  fs::path partial = opt.out;
  partial += ".partial";
  fs::remove(partial, ec);
  try {
    auto out = acq::ResultsFile::create(partial, opt.software);
    for (std::size_t k = 0; k < opt.inputs.size(); ++k) {
      std::vector<std::string> keys;
      for (const auto& [key, c] : chosen)
        if (c.input == k) keys.push_back(key);
      if (!keys.empty()) out.copy_from(opt.inputs[k], keys);
    }
    out.close();
  } catch (...) {
    fs::remove(partial, ec);  // never leave a half merge behind
    throw;
  }
  fs::rename(partial, opt.out, ec);
  if (ec)
    throw std::runtime_error("replay-merge: cannot rename " + partial.string() + " to " +
                             opt.out.string() + ": " + ec.message());
  for (const auto& [key, c] : chosen) (c.status == "ok" ? sum.ok : sum.failed)++;
  sum.records = chosen.size();

  if (opt.jsonl) {
    std::ofstream f(*opt.jsonl, std::ios::trunc);
    if (!f) throw std::invalid_argument("--jsonl: cannot write " + opt.jsonl->string());
    acq::for_each_result(opt.out,
                         [&](const acq::ResultRecord& r) { f << jobs::json_text(record_json(r)) << "\n"; });
    if (!f.flush()) throw std::runtime_error("--jsonl: cannot write " + opt.jsonl->string());
  }
  if (opt.report_dir) {
    write_batch_summary(opt.out, *opt.report_dir);
    write_index(opt.out, *opt.report_dir);
  }
  return sum;
}

}  // namespace piezo::jobs::replay
