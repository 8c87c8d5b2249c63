#pragma once
// Which captures a replay covers: the inputs (files taken as given, folders
// searched recursively for *.h5 / *.hdf5), and the deterministic shard of
// them that one job of a scale-out run replays.
#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace piezo::jobs::replay {

struct ShardSpec {
  std::size_t index = 0;  // 0 <= index < count
  std::size_t count = 1;
};

// "I/N" with 0 <= I < N (Slurm: $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT
// with --array=0-(N-1)). Throws std::invalid_argument saying what is wrong.
ShardSpec parse_shard(std::string_view text);

// Every capture under `inputs`: lexically normalised paths (relative stays
// relative), one entry per file (aliases through "..", "." or symlinks
// collapse), sorted by their text, `exclude` left out (the results file).
// A folder's files are found recursively, symlinked folders not followed.
// Throws std::invalid_argument naming an input that does not exist.
std::vector<std::filesystem::path> find_captures(
    const std::vector<std::string>& inputs, const std::vector<std::filesystem::path>& exclude = {});

// The captures of one shard: position k of the sorted list goes to shard
// k mod N. Depends only on the sorted list, never on --jobs, directory
// listing order or the machine; the shards are disjoint and cover the list.
std::vector<std::filesystem::path> select_shard(const std::vector<std::filesystem::path>& sorted,
                                                const ShardSpec& shard);

}  // namespace piezo::jobs::replay
