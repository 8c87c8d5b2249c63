#include "jobs/replay/discover.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <set>
#include <stdexcept>

namespace piezo::jobs::replay {

namespace fs = std::filesystem;

namespace {

std::size_t parse_count(std::string_view s, std::string_view text) {
  std::size_t v = 0;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || p != s.data() + s.size())
    throw std::invalid_argument("--shard '" + std::string(text) +
                                "': expected I/N with whole numbers, e.g. 0/4");
  return v;
}

bool is_capture_name(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".h5" || ext == ".hdf5";
}

fs::path identity(const fs::path& p) {
  std::error_code ec;
  fs::path c = fs::weakly_canonical(p, ec);
  return ec ? fs::absolute(p).lexically_normal() : c;
}

}  // namespace

ShardSpec parse_shard(std::string_view text) {
  const auto slash = text.find('/');
  if (slash == std::string_view::npos)
    throw std::invalid_argument("--shard '" + std::string(text) + "': expected I/N, e.g. 0/4");
  ShardSpec s{parse_count(text.substr(0, slash), text), parse_count(text.substr(slash + 1), text)};
  if (s.count == 0)
    throw std::invalid_argument("--shard '" + std::string(text) + "': N must be at least 1");
  if (s.index >= s.count)
    throw std::invalid_argument("--shard '" + std::string(text) + "': I must be in 0.." +
                                std::to_string(s.count - 1) + " (shards are numbered from 0)");
  return s;
}

std::vector<fs::path> find_captures(const std::vector<std::string>& inputs,
                                    const std::vector<fs::path>& exclude) {
  std::vector<fs::path> found;
  for (const auto& in : inputs) {
    const fs::path p = fs::path(in).lexically_normal();
    std::error_code ec;
    const auto st = fs::status(p, ec);
    if (ec || !fs::exists(st)) throw std::invalid_argument(in + ": no such file or folder");
    if (!fs::is_directory(st)) {
      found.push_back(p);  // a file named explicitly is replayed whatever its extension
      continue;
    }
    fs::recursive_directory_iterator it(p, fs::directory_options::skip_permission_denied, ec), end;
    if (ec) throw std::invalid_argument(in + ": cannot list folder: " + ec.message());
    for (; it != end; it.increment(ec)) {
      if (ec) throw std::invalid_argument(in + ": cannot list folder: " + ec.message());
      std::error_code fec;
      if (it->is_regular_file(fec) && is_capture_name(it->path()))
        found.push_back(it->path().lexically_normal());
    }
  }
  std::sort(found.begin(), found.end(),
            [](const fs::path& a, const fs::path& b) { return a.string() < b.string(); });
  std::set<fs::path> seen;
  for (const auto& e : exclude) seen.insert(identity(e));
  std::vector<fs::path> out;
  for (const auto& p : found)
    if (seen.insert(identity(p)).second) out.push_back(p);
  return out;
}

std::vector<fs::path> select_shard(const std::vector<fs::path>& sorted, const ShardSpec& shard) {
  if (shard.count == 0 || shard.index >= shard.count)
    throw std::invalid_argument("--shard: bad shard (I/N with I < N)");
  std::vector<fs::path> out;
  for (std::size_t k = shard.index; k < sorted.size(); k += shard.count) out.push_back(sorted[k]);
  return out;
}

}  // namespace piezo::jobs::replay
