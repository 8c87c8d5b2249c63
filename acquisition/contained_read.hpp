#pragma once
// Reading a capture where a crash costs only that file.
//
// Debian's libhdf5 (1.10) crashes on some damaged files (SIGSEGV in
// H5HG_read <- H5T__conv_vlen <- H5Aread on a byte-flipped global heap, an
// abort in the metadata cache, ...); that is not ours to fix, and a reader
// cannot validate a file before HDF5 has parsed it. So a capture that did not
// come from this process is first read in a forked child: if the child dies of
// a signal or does not finish, the file is refused with a CaptureError that
// says so ("the HDF5 library crashed reading ..."), and the caller, which is
// still alive, goes on. When the child read the file without crashing, the
// same deterministic read is done again here (the cost: one more read of a
// file that is in the page cache).
//
// The fork happens under the project's HDF5 lock (h5_handle.hpp), so no other
// thread of this process is inside HDF5 at that moment and the child's copy of
// the library is consistent; the child renews its copy of the lock (which names
// the parent's thread) before it reads, and ends with _exit (no atexit
// handlers: it never flushes or closes anything the parent has open).
#include <cstdint>
#include <filesystem>

#include "acquisition/capture.hpp"
#include "acquisition/capture_file.hpp"

namespace piezo::acq {

struct ContainedReadOptions {
  ReadOptions read;
  double timeout_s = 120.0;  // a read that takes longer is a hang: the child is killed
};

// Reads `file` in a child process and reports how that went: throws
// CaptureError for a file that crashed or hung the reader (or one the reader
// refuses: the same message read_capture gives). Returns normally when the file
// reads without crashing.
void probe_capture(const std::filesystem::path& file, const ContainedReadOptions& opt = {});

// probe_capture, then read_capture in this process.
Capture read_capture_contained(const std::filesystem::path& file,
                               const ContainedReadOptions& opt = {});

// Caps this process's address space (RLIMIT_AS, soft limit) at its present
// size plus what reading and processing a capture file of `file_bytes` can
// legitimately need: 2 GiB for the work itself, plus 4400 × the file (samples
// stored down to 1/1100 when compressed, the reader's own bound, as doubles
// beside their float32 copy). For the processes that contain a read (the probe
// child, the replay workers): a damaged variable-length string whose stored
// length says gigabytes made libhdf5 allocate and clear 22 GB for a 67 kB file
// (90 s, the machine nearly out of memory); under the cap the allocation fails
// at once and the file is refused with libhdf5's "memory allocation failed".
// The hard limit is not touched, so a later, larger file raises the cap again.
// No-op under AddressSanitizer, whose shadow memory reserves terabytes of
// address space.
void limit_memory_for_capture(std::uintmax_t file_bytes);

// Turns a child's end (waitpid status) into words: "SIGSEGV (segmentation fault)".
std::string describe_signal(int signal_number);

}  // namespace piezo::acq
