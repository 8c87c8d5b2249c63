#include "acquisition/h5_handle.hpp"

#include <new>

namespace piezo::acq::h5 {

std::recursive_mutex& h5_mutex() {
  static std::recursive_mutex m;
  return m;
}

void renew_h5_mutex_in_forked_child() {
  // The old object is not destroyed: its owner does not exist in this process.
  new (&h5_mutex()) std::recursive_mutex();
}

void quiet_errors() {
  static std::once_flag once;
  std::call_once(once, [] { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); });
}

namespace {
herr_t walk_cb(unsigned n, const H5E_error2_t* err, void* data) {
  auto* out = static_cast<std::string*>(data);
  // The innermost frame (n == 0) is usually the most specific cause.
  if (n == 0 && err && err->desc) *out = err->desc;
  return 0;
}
}  // namespace

std::string last_error() {
  std::string msg;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, walk_cb, &msg);
  H5Eclear2(H5E_DEFAULT);
  return msg;
}

}  // namespace piezo::acq::h5
