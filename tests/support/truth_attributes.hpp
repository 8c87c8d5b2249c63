#pragma once
// Test support: a number attribute of a capture's /truth group, read with the
// HDF5 C API (tests only: estimators never read /truth). NaN when absent.
#include <hdf5.h>

#include <cmath>
#include <filesystem>

namespace piezo::test {

inline double truth_number(const std::filesystem::path& file, const char* name) {
  hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  double v = std::nan("");
  if (f >= 0 && H5Aexists_by_name(f, "truth", name, H5P_DEFAULT) > 0) {
    hid_t a = H5Aopen_by_name(f, "truth", name, H5P_DEFAULT, H5P_DEFAULT);
    H5Aread(a, H5T_NATIVE_DOUBLE, &v);
    H5Aclose(a);
  }
  if (f >= 0) H5Fclose(f);
  return v;
}

}  // namespace piezo::test
