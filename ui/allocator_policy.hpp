#pragma once
// The programs' allocator policy (issue 43): glibc's malloc returns blocks
// above its mmap threshold (128 KiB at first, moving up to 32 MiB) to the
// kernel at every free and its heap top above 128 KiB, so a replay that builds
// and drops the FE port model's matrices and the fit's work vectors thousands
// of times pays a page fault per page each time: 25 % of a replayed capture's
// time went to page faults and the zeroing of fresh pages (perf, refsim-v1/12;
// docs/benchmarks.md). Kept mapped instead, the same capture replays in
// 0.55 s for 0.90-0.97 s; the peak memory is the same (49 MB), since the blocks are
// reused, not added. Called first in main() of piezobench and piezobench-gui.
#include <malloc.h>

namespace piezo::ui {

inline void set_allocator_policy() {
  mallopt(M_MMAP_THRESHOLD, 256 << 20);  // blocks up to 256 MiB from the heap, reused after free
  mallopt(M_TRIM_THRESHOLD, 512 << 20);  // keep up to 512 MiB of freed heap top mapped
  mallopt(M_TOP_PAD, 64 << 20);          // grow the heap 64 MiB at a time
}

}  // namespace piezo::ui
