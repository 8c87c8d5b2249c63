// Which captures a replay covers and how shards split them: recursive search,
// one entry per file, sorted; shards disjoint, covering and independent of the
// order of the inputs.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>

#include "jobs/replay/discover.hpp"

using namespace piezo;
namespace fs = std::filesystem;

namespace {
struct Tree {
  fs::path root = fs::temp_directory_path() / ("piezobench-discover-" + std::to_string(::getpid()));
  Tree() {
    fs::remove_all(root);
    for (const char* f : {"line1/T-002.h5", "line1/T-001.h5", "line2/deep/T-010.hdf5",
                          "line2/notes.txt", "line2/T-003.h5.partial", "other/extra.dat"}) {
      fs::create_directories((root / f).parent_path());
      std::ofstream(root / f) << "x";
    }
  }
  ~Tree() { fs::remove_all(root); }
  std::string s(const char* rel) const { return (root / rel).lexically_normal().string(); }
};

std::vector<std::string> strings(const std::vector<fs::path>& v) {
  std::vector<std::string> out;
  for (const auto& p : v) out.push_back(p.string());
  return out;
}
}  // namespace

TEST(Discover, FoldersRecursivelyFilesAsGivenSortedOnce) {
  Tree t;
  auto found = jobs::replay::find_captures(
      {t.s("line2"), t.s("other/extra.dat"), t.s("line1"), t.root.string() + "/line1/./T-001.h5"});
  EXPECT_EQ(strings(found),
            (std::vector<std::string>{t.s("line1/T-001.h5"), t.s("line1/T-002.h5"),
                                      t.s("line2/deep/T-010.hdf5"), t.s("other/extra.dat")}));
}

TEST(Discover, ExcludesTheResultsFileAndNamesAMissingInput) {
  Tree t;
  auto found = jobs::replay::find_captures({t.s("line1")}, {t.root / "line1/../line1/T-002.h5"});
  EXPECT_EQ(strings(found), (std::vector<std::string>{t.s("line1/T-001.h5")}));
  try {
    jobs::replay::find_captures({t.s("line1"), t.s("nope")});
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(t.s("nope")), std::string::npos) << e.what();
  }
}

TEST(Shard, ParsesIOverN) {
  auto s = jobs::replay::parse_shard("3/4");
  EXPECT_EQ(s.index, 3u);
  EXPECT_EQ(s.count, 4u);
  for (const char* bad : {"4/4", "1/0", "x/4", "1", "-1/4", "1/4/2", "/4", "1/"})
    EXPECT_THROW(jobs::replay::parse_shard(bad), std::invalid_argument) << bad;
}

TEST(Shard, DisjointCoveringBalancedAndOrderIndependent) {
  Tree t;
  const auto a = jobs::replay::find_captures({t.s("line1"), t.s("line2"), t.s("other/extra.dat")});
  const auto b = jobs::replay::find_captures({t.s("other/extra.dat"), t.s("line2"), t.s("line1")});
  ASSERT_EQ(a, b);
  std::vector<fs::path> all;
  for (std::size_t i = 0; i < 3; ++i) {
    auto part = jobs::replay::select_shard(a, {i, 3});
    EXPECT_GE(part.size(), 1u);
    EXPECT_LE(part.size(), 2u);
    all.insert(all.end(), part.begin(), part.end());
  }
  std::sort(all.begin(), all.end());
  EXPECT_EQ(all, a);
  EXPECT_EQ(std::set<fs::path>(all.begin(), all.end()).size(), all.size());
  // Position k of the sorted list goes to shard k mod N.
  std::vector<fs::path> ten;
  for (char k = '0'; k <= '9'; ++k) ten.emplace_back(std::string("c") + k + ".h5");
  auto s1 = jobs::replay::select_shard(ten, {1, 4});
  EXPECT_EQ(strings(s1), (std::vector<std::string>{"c1.h5", "c5.h5", "c9.h5"}));
  EXPECT_EQ(jobs::replay::select_shard(ten, {0, 1}), ten);
}
