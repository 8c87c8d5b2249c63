#include "tests/support/capture_mutations.hpp"

#include <hdf5.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "acquisition/capture_file.hpp"

namespace piezo::test {

namespace fs = std::filesystem;

const std::vector<DefectCase>& all_defects() {
  static const std::vector<DefectCase> cases = {
      {Defect::MissingFormat, "missing_format", "/format", "missing"},
      {Defect::WrongFormatName, "wrong_format_name", "/format", "expected \"piezo-capture\""},
      {Defect::WrongFormatVersion, "wrong_format_version", "/format_version", "unsupported version 2"},
      {Defect::MissingSetup, "missing_setup", "/setup", "missing required group"},
      {Defect::MissingR1, "missing_r1", "/setup/divider_r1_ohm", "missing"},
      {Defect::ZeroR1, "zero_r1", "/setup/divider_r1_ohm", "positive"},
      {Defect::NegativeR1, "negative_r1", "/setup/divider_r1_ohm", "positive"},
      {Defect::ZeroSampleRate, "zero_rate", "/shots/000001/sample_rate_hz", "positive"},
      {Defect::NegativeSampleRate, "negative_rate", "/shots/000001/sample_rate_hz", "positive"},
      {Defect::MissingSampleRate, "missing_rate", "/shots/000001/sample_rate_hz", "missing"},
      {Defect::UnknownExcitation, "unknown_excitation", "/shots/000001/excitation", "unknown"},
      {Defect::MissingV1, "missing_v1", "/shots/000001/v1", "missing dataset"},
      {Defect::MissingV2, "missing_v2", "/shots/000001/v2", "missing dataset"},
      {Defect::IntegerDtype, "integer_dtype", "/shots/000001/v2", "integer"},
      {Defect::StringDtype, "string_dtype", "/shots/000001/v2", "string"},
      {Defect::TwoDimensional, "two_dimensional", "/shots/000001/v1", "rank 2"},
      {Defect::LengthMismatch, "length_mismatch", "/shots/000001", "length mismatch"},
      {Defect::TooShort, "too_short", "/shots/000001/v1", "too short"},
      {Defect::NaNSample, "nan_sample", "/shots/000001/v1", "NaN at sample 5"},
      {Defect::InfSample, "inf_sample", "/shots/000001/v2", "Inf at sample 7"},
      {Defect::EmptyShots, "empty_shots", "/shots", "no shots"},
      {Defect::Truncated, "truncated", "/", "HDF5"},
      // Issue 16: plausibility. One sample of 3.5e11 V on a channel declared +-2 V.
      {Defect::OutOfRangeSample, "out_of_range_sample", "/shots/000001/v1",
       "outside the declared range"},
      {Defect::TinySampleRate, "tiny_rate", "/shots/000001/sample_rate_hz", "implausible sample rate"},
      {Defect::HugeSampleRate, "huge_rate", "/shots/000001/sample_rate_hz", "implausible sample rate"},
      {Defect::AbsurdLength, "absurd_length", "/shots/000001/v1", "implausible length"},
      {Defect::BadAdcBits, "bad_adc_bits", "/shots/000001/adc_bits", "must be 1..32"},
      {Defect::NotHdf5, "not_hdf5", "/", "not a readable HDF5 file"},
      {Defect::Directory, "directory", "/", "is a directory"},
      {Defect::MissingPath, "missing_path", "/", "no such file"},
  };
  return cases;
}

acq::Capture small_valid_capture(std::size_t n) {
  acq::Capture cap;
  cap.setup.divider_r1_ohm = 3140.0;
  cap.setup.transducer_id = "T-001";
  cap.setup.material = "apc850";
  cap.setup.inner_diameter_m = 0.016;
  cap.setup.outer_diameter_m = 0.019;
  cap.setup.length_m = 0.02;
  cap.setup.density_kg_m3 = 7600;
  cap.setup.notes = "unit test";
  for (int k = 0; k < 2; ++k) {
    acq::Shot s;
    s.sample_rate_hz = 1e7;
    s.excitation = acq::Excitation::ExpDecay;
    s.amplitude_v = 1.0;
    s.decay_per_s = 3000.0;
    s.pretrigger_samples = 4;
    s.v1.resize(n);
    s.v2.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      s.v1[i] = i < 4 ? 0.0 : std::exp(-3000.0 * (i - 4) / 1e7);
      s.v2[i] = 0.25 * s.v1[i] * std::cos(0.1 * i + k);
    }
    cap.shots.push_back(s);
  }
  return cap;
}

namespace {

void check(herr_t r, const char* what) {
  if (r < 0) throw std::runtime_error(std::string("capture_mutations: HDF5 failed: ") + what);
}

void set_double_attr(hid_t obj, const char* name, double v) {
  if (H5Aexists(obj, name) > 0) check(H5Adelete(obj, name), name);
  hid_t sp = H5Screate(H5S_SCALAR);
  hid_t a = H5Acreate2(obj, name, H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT);
  check(H5Awrite(a, H5T_NATIVE_DOUBLE, &v), name);
  H5Aclose(a);
  H5Sclose(sp);
}

void set_int_attr(hid_t obj, const char* name, long long v) {
  if (H5Aexists(obj, name) > 0) check(H5Adelete(obj, name), name);
  hid_t sp = H5Screate(H5S_SCALAR);
  hid_t a = H5Acreate2(obj, name, H5T_STD_I64LE, sp, H5P_DEFAULT, H5P_DEFAULT);
  check(H5Awrite(a, H5T_NATIVE_LLONG, &v), name);
  H5Aclose(a);
  H5Sclose(sp);
}

void set_string_attr(hid_t obj, const char* name, const char* v) {
  if (H5Aexists(obj, name) > 0) check(H5Adelete(obj, name), name);
  hid_t t = H5Tcopy(H5T_C_S1);
  H5Tset_size(t, std::strlen(v) + 1);  // fixed-length, as some tools write
  hid_t sp = H5Screate(H5S_SCALAR);
  hid_t a = H5Acreate2(obj, name, t, sp, H5P_DEFAULT, H5P_DEFAULT);
  check(H5Awrite(a, t, v), name);
  H5Aclose(a);
  H5Sclose(sp);
  H5Tclose(t);
}

void replace_dataset_f64(hid_t g, const char* name, const std::vector<double>& v,
                         std::vector<hsize_t> dims = {}) {
  if (H5Lexists(g, name, H5P_DEFAULT) > 0) check(H5Ldelete(g, name, H5P_DEFAULT), name);
  if (dims.empty()) dims = {v.size()};
  hid_t sp = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
  hid_t d = H5Dcreate2(g, name, H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  check(H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), name);
  H5Dclose(d);
  H5Sclose(sp);
}

void replace_dataset_int(hid_t g, const char* name, std::size_t n) {
  check(H5Ldelete(g, name, H5P_DEFAULT), name);
  std::vector<int> v(n, 7);
  hsize_t dim = n;
  hid_t sp = H5Screate_simple(1, &dim, nullptr);
  hid_t d = H5Dcreate2(g, name, H5T_STD_I32LE, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  check(H5Dwrite(d, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), name);
  H5Dclose(d);
  H5Sclose(sp);
}

void replace_dataset_string(hid_t g, const char* name, std::size_t n) {
  check(H5Ldelete(g, name, H5P_DEFAULT), name);
  hid_t t = H5Tcopy(H5T_C_S1);
  H5Tset_size(t, 4);
  std::vector<char> buf(n * 4, 'a');
  hsize_t dim = n;
  hid_t sp = H5Screate_simple(1, &dim, nullptr);
  hid_t d = H5Dcreate2(g, name, t, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  check(H5Dwrite(d, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()), name);
  H5Dclose(d);
  H5Sclose(sp);
  H5Tclose(t);
}

}  // namespace

void make_capture_with_defect(const fs::path& file, Defect d) {
  std::error_code ec;
  fs::remove_all(file, ec);
  if (d == Defect::MissingPath) return;
  if (d == Defect::Directory) {
    fs::create_directories(file);
    return;
  }
  if (d == Defect::NotHdf5) {
    std::ofstream(file) << "f_hz,re_ohm,im_ohm\n1000,1,2\n";
    return;
  }
  const auto cap = small_valid_capture();
  acq::write_capture(file, cap);
  if (d == Defect::None) return;
  if (d == Defect::Truncated) {
    fs::resize_file(file, fs::file_size(file) / 2);
    return;
  }
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (f < 0) throw std::runtime_error("capture_mutations: cannot reopen " + file.string());
  hid_t setup = H5Gopen2(f, "setup", H5P_DEFAULT);
  hid_t shots = H5Gopen2(f, "shots", H5P_DEFAULT);
  hid_t shot = H5Gopen2(shots, "000001", H5P_DEFAULT);
  const std::size_t n = cap.shots[1].v1.size();
  std::vector<double> v1 = cap.shots[1].v1, v2 = cap.shots[1].v2;
  switch (d) {
    case Defect::MissingFormat: check(H5Adelete(f, "format"), "format"); break;
    case Defect::WrongFormatName: set_string_attr(f, "format", "other-format"); break;
    case Defect::WrongFormatVersion: set_int_attr(f, "format_version", 2); break;
    case Defect::MissingSetup: check(H5Ldelete(f, "setup", H5P_DEFAULT), "setup"); break;
    case Defect::MissingR1: check(H5Adelete(setup, "divider_r1_ohm"), "r1"); break;
    case Defect::ZeroR1: set_double_attr(setup, "divider_r1_ohm", 0.0); break;
    case Defect::NegativeR1: set_double_attr(setup, "divider_r1_ohm", -3140.0); break;
    case Defect::ZeroSampleRate: set_double_attr(shot, "sample_rate_hz", 0.0); break;
    case Defect::NegativeSampleRate: set_double_attr(shot, "sample_rate_hz", -1e7); break;
    case Defect::MissingSampleRate: check(H5Adelete(shot, "sample_rate_hz"), "rate"); break;
    case Defect::UnknownExcitation: set_string_attr(shot, "excitation", "square"); break;
    case Defect::MissingV1: check(H5Ldelete(shot, "v1", H5P_DEFAULT), "v1"); break;
    case Defect::MissingV2: check(H5Ldelete(shot, "v2", H5P_DEFAULT), "v2"); break;
    case Defect::IntegerDtype: replace_dataset_int(shot, "v2", n); break;
    case Defect::StringDtype: replace_dataset_string(shot, "v2", n); break;
    case Defect::TwoDimensional: replace_dataset_f64(shot, "v1", v1, {n / 2, 2}); break;
    case Defect::LengthMismatch:
      v2.pop_back();
      replace_dataset_f64(shot, "v2", v2);
      break;
    case Defect::TooShort:
      v1.resize(8);
      v2.resize(8);
      replace_dataset_f64(shot, "v1", v1);
      replace_dataset_f64(shot, "v2", v2);
      break;
    case Defect::NaNSample:
      v1[5] = std::numeric_limits<double>::quiet_NaN();
      replace_dataset_f64(shot, "v1", v1);
      break;
    case Defect::InfSample:
      v2[7] = -std::numeric_limits<double>::infinity();
      replace_dataset_f64(shot, "v2", v2);
      break;
    case Defect::OutOfRangeSample:
      set_double_attr(shot, "v1_range_v", 2.0);
      v1[11] = 3.5e11;
      replace_dataset_f64(shot, "v1", v1);
      break;
    case Defect::TinySampleRate: set_double_attr(shot, "sample_rate_hz", 1e-300); break;
    case Defect::HugeSampleRate: set_double_attr(shot, "sample_rate_hz", 1e300); break;
    case Defect::AbsurdLength: {
      // Declared 2^40 samples (8 TiB as float64), never written: the reader
      // must refuse it from the shape, before allocating anything.
      for (const char* ch : {"v1", "v2"}) {
        check(H5Ldelete(shot, ch, H5P_DEFAULT), ch);
        hsize_t dim = hsize_t(1) << 40;
        hid_t sp = H5Screate_simple(1, &dim, nullptr);
        hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
        hsize_t chunk = 1024;
        H5Pset_chunk(dcpl, 1, &chunk);
        hid_t ds = H5Dcreate2(shot, ch, H5T_IEEE_F32LE, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
        if (ds < 0) throw std::runtime_error(std::string("capture_mutations: cannot create ") + ch);
        H5Dclose(ds);
        H5Pclose(dcpl);
        H5Sclose(sp);
      }
      break;
    }
    case Defect::BadAdcBits: set_int_attr(shot, "adc_bits", 0); break;
    case Defect::EmptyShots:
      H5Gclose(shot);
      shot = -1;
      check(H5Ldelete(shots, "000000", H5P_DEFAULT), "000000");
      check(H5Ldelete(shots, "000001", H5P_DEFAULT), "000001");
      break;
    default: break;
  }
  if (shot >= 0) H5Gclose(shot);
  H5Gclose(shots);
  H5Gclose(setup);
  H5Fclose(f);
}

void add_ignorable_extras(const fs::path& file) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (f < 0) throw std::runtime_error("capture_mutations: cannot reopen " + file.string());
  hid_t truth = H5Gcreate2(f, "truth", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  set_double_attr(truth, "YE11", 6.66e10);
  replace_dataset_f64(truth, "z_re", {1.0, 2.0, 3.0});
  H5Gclose(truth);
  set_string_attr(f, "vendor_note", "written by a test");
  hid_t setup = H5Gopen2(f, "setup", H5P_DEFAULT);
  set_double_attr(setup, "temperature_c", 23.5);
  H5Gclose(setup);
  hid_t shots = H5Gopen2(f, "shots", H5P_DEFAULT);
  hid_t extra = H5Gcreate2(shots, "README", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  H5Gclose(extra);
  hid_t shot = H5Gopen2(shots, "000000", H5P_DEFAULT);
  set_int_attr(shot, "vendor_trigger_count", 17);
  replace_dataset_f64(shot, "v3", {0.0, 1.0});
  H5Gclose(shot);
  H5Gclose(shots);
  H5Fclose(f);
}

bool strip_truth(const fs::path& file) {
  hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (f < 0) throw std::runtime_error("strip_truth: cannot open " + file.string());
  const bool had = H5Lexists(f, "truth", H5P_DEFAULT) > 0;
  if (had) H5Ldelete(f, "truth", H5P_DEFAULT);
  H5Fclose(f);
  return had;
}

}  // namespace piezo::test
