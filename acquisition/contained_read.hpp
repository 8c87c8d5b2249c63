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

// Turns a child's end (waitpid status) into words: "SIGSEGV (segmentation fault)".
std::string describe_signal(int signal_number);

}  // namespace piezo::acq
