#pragma once
// RAII for HDF5 identifiers and the library-wide lock. Internal to acquisition/:
// Debian's libhdf5 is built without thread safety, so every HDF5 call of the
// project runs under h5_mutex().
#include <hdf5.h>

#include <mutex>
#include <string>
#include <utility>

namespace piezo::acq::h5 {

std::recursive_mutex& h5_mutex();

// In a child made by fork() while this thread held h5_mutex(): the child's copy
// of the lock still names the parent's thread (glibc records the kernel thread
// id, which the child's only thread does not have), so it is made anew,
// unlocked. Call it first thing in the child, nowhere else.
void renew_h5_mutex_in_forked_child();

// Silences HDF5's own error printing (we report errors ourselves); idempotent.
void quiet_errors();

// The most specific message on HDF5's current error stack ("" if none).
std::string last_error();

class Id {
 public:
  using Closer = herr_t (*)(hid_t);
  Id() = default;
  Id(hid_t id, Closer c) : id_(id), close_(c) {}
  Id(Id&& o) noexcept : id_(std::exchange(o.id_, H5I_INVALID_HID)), close_(o.close_) {}
  Id& operator=(Id&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, H5I_INVALID_HID);
      close_ = o.close_;
    }
    return *this;
  }
  ~Id() { reset(); }
  void reset() {
    if (id_ >= 0 && close_) close_(id_);
    id_ = H5I_INVALID_HID;
  }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  explicit operator bool() const { return valid(); }

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer close_ = nullptr;
};

inline Id file(hid_t id) { return Id(id, H5Fclose); }
inline Id group(hid_t id) { return Id(id, H5Gclose); }
inline Id dataset(hid_t id) { return Id(id, H5Dclose); }
inline Id attribute(hid_t id) { return Id(id, H5Aclose); }
inline Id dataspace(hid_t id) { return Id(id, H5Sclose); }
inline Id datatype(hid_t id) { return Id(id, H5Tclose); }
inline Id plist(hid_t id) { return Id(id, H5Pclose); }

}  // namespace piezo::acq::h5
