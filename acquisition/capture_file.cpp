// piezo-capture/1 reading and writing through the HDF5 C library.
// Schema: ../shared/capture-format.md. Every violation is a CaptureError
// naming the file, the path inside it and the problem.
#include "acquisition/capture_file.hpp"
#include "acquisition/utf8.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <algorithm>
#include <system_error>

#include "acquisition/h5_handle.hpp"

namespace piezo::acq {

namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------- reading

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}
  // Samples per channel the shots still to be read may hold (kMaxCaptureSamples in all).
  void limit_total(std::size_t* budget) { budget_ = budget; }

  [[noreturn]] void fail(const std::string& path, const std::string& problem) const {
    throw CaptureError(file_, path, problem);
  }

  // Attribute `name` on object `obj` (whose path is `where`): nullopt if absent.
  h5::Id open_attr(hid_t obj, const char* name, const std::string& where) const {
    htri_t ex = H5Aexists(obj, name);
    if (ex < 0) fail(where, std::string("cannot query attribute ") + name + ": " + h5::last_error());
    if (ex == 0) return {};
    h5::Id a = h5::attribute(H5Aopen(obj, name, H5P_DEFAULT));
    if (!a) fail(attr_path(where, name), "cannot open attribute: " + h5::last_error());
    h5::Id space = h5::dataspace(H5Aget_space(a.get()));
    if (H5Sget_simple_extent_npoints(space.get()) != 1)
      fail(attr_path(where, name), "must be a scalar");
    return a;
  }

  static std::string attr_path(const std::string& where, const char* name) {
    return (where == "/" ? "/" : where + "/") + name;
  }

  std::optional<std::string> string_attr(hid_t obj, const char* name, const std::string& where) const {
    h5::Id a = open_attr(obj, name, where);
    if (!a) return std::nullopt;
    h5::Id type = h5::datatype(H5Aget_type(a.get()));
    if (H5Tget_class(type.get()) != H5T_STRING)
      fail(attr_path(where, name), "wrong type: expected a string");
    std::string out;
    if (H5Tis_variable_str(type.get()) > 0) {
      h5::Id mem = h5::datatype(H5Tcopy(H5T_C_S1));
      H5Tset_size(mem.get(), H5T_VARIABLE);
      H5Tset_cset(mem.get(), H5Tget_cset(type.get()));
      char* p = nullptr;
      if (H5Aread(a.get(), mem.get(), &p) < 0)
        fail(attr_path(where, name), "cannot read string: " + h5::last_error());
      if (p) {
        out = p;
        H5free_memory(p);
      }
    } else {
      std::size_t n = H5Tget_size(type.get());
      std::string buf(n, '\0');
      h5::Id mem = h5::datatype(H5Tcopy(type.get()));
      if (H5Aread(a.get(), mem.get(), buf.data()) < 0)
        fail(attr_path(where, name), "cannot read string: " + h5::last_error());
      out = buf.substr(0, buf.find('\0'));
      while (!out.empty() && out.back() == ' ') out.pop_back();  // space-padded strings
    }
    return utf8_or_replaced(out);
  }

  // A float64 attribute; integer-typed values are accepted (exactly representable numbers).
  std::optional<double> double_attr(hid_t obj, const char* name, const std::string& where) const {
    h5::Id a = open_attr(obj, name, where);
    if (!a) return std::nullopt;
    h5::Id type = h5::datatype(H5Aget_type(a.get()));
    H5T_class_t cls = H5Tget_class(type.get());
    if (cls != H5T_FLOAT && cls != H5T_INTEGER)
      fail(attr_path(where, name), "wrong type: expected a number (float64)");
    double v = 0;
    if (H5Aread(a.get(), H5T_NATIVE_DOUBLE, &v) < 0)
      fail(attr_path(where, name), "cannot read: " + h5::last_error());
    if (!std::isfinite(v)) fail(attr_path(where, name), "not a finite number");
    return v;
  }

  std::optional<std::int64_t> int_attr(hid_t obj, const char* name, const std::string& where) const {
    h5::Id a = open_attr(obj, name, where);
    if (!a) return std::nullopt;
    h5::Id type = h5::datatype(H5Aget_type(a.get()));
    if (H5Tget_class(type.get()) != H5T_INTEGER)
      fail(attr_path(where, name), "wrong type: expected an integer");
    std::int64_t v = 0;
    if (H5Aread(a.get(), H5T_NATIVE_INT64, &v) < 0)
      fail(attr_path(where, name), "cannot read: " + h5::last_error());
    return v;
  }

  bool has_link(hid_t loc, const char* name) const {
    htri_t ex = H5Lexists(loc, name, H5P_DEFAULT);
    return ex > 0;
  }

  // v1 / v2: rank-1 float32/float64 dataset.
  std::vector<double> signal(hid_t shot, const char* name, const std::string& where, bool load,
                             std::size_t* n_out) const {
    const std::string p = where + "/" + name;
    if (!has_link(shot, name)) fail(p, "missing dataset");
    H5O_info_t info;
    if (H5Oget_info_by_name(shot, name, &info, H5P_DEFAULT) < 0 || info.type != H5O_TYPE_DATASET)
      fail(p, "not a dataset");
    h5::Id ds = h5::dataset(H5Dopen2(shot, name, H5P_DEFAULT));
    if (!ds) fail(p, "cannot open dataset: " + h5::last_error());
    h5::Id type = h5::datatype(H5Dget_type(ds.get()));
    H5T_class_t cls = H5Tget_class(type.get());
    std::size_t sz = H5Tget_size(type.get());
    if (cls != H5T_FLOAT || (sz != 4 && sz != 8)) {
      const char* what = cls == H5T_INTEGER  ? "integer"
                         : cls == H5T_STRING ? "string"
                         : cls == H5T_FLOAT  ? "float of unsupported size"
                                             : "non-numeric";
      fail(p, std::string("wrong dtype: ") + what + ", expected float32 or float64");
    }
    h5::Id space = h5::dataspace(H5Dget_space(ds.get()));
    int rank = H5Sget_simple_extent_ndims(space.get());
    if (rank != 1) fail(p, "wrong shape: rank " + std::to_string(rank) + ", expected [N]");
    hsize_t n = 0;
    H5Sget_simple_extent_dims(space.get(), &n, nullptr);
    *n_out = static_cast<std::size_t>(n);
    if (n > kMaxSamples)
      fail(p, "implausible length: " + std::to_string(n) + " samples (this reader takes at most " +
                  std::to_string(kMaxSamples) + " per signal)");
    // A signal must be recorded: a dataset that declares N samples but stores
    // fewer bytes than they need (never written, or cut short) is refused
    // before anything is allocated. Compressed chunks may store less, but no
    // HDF5 filter shrinks data by more than deflate's ~1030:1.
    if (n > 0) {
      h5::Id dcpl = h5::plist(H5Dget_create_plist(ds.get()));
      const int filters = dcpl ? H5Pget_nfilters(dcpl.get()) : 0;
      const double stored = static_cast<double>(H5Dget_storage_size(ds.get()));
      const double needed = static_cast<double>(n) * static_cast<double>(sz);
      if (stored * (filters > 0 ? 1100.0 : 1.0) < needed)
        fail(p, "declares " + std::to_string(n) + " samples but the file stores " +
                    std::to_string(static_cast<long long>(stored)) + " of the " +
                    std::to_string(static_cast<long long>(needed)) +
                    " bytes they need (never written, or truncated)");
    }
    std::vector<double> v;
    if (!load || n == 0) return v;
    v.resize(n);
    if (sz == 4) {
      // float32 samples read as they are stored and widened here (exact, as
      // HDF5's own float→double conversion is): a read into doubles goes
      // through a 1 MiB conversion buffer that libhdf5 allocates and clears
      // on every H5Dread, a tenth of a capture's read time (issue 43).
      std::vector<float> f(n);
      if (H5Dread(ds.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, f.data()) < 0)
        fail(p, "cannot read samples (damaged or truncated file?): " + h5::last_error());
      std::copy(f.begin(), f.end(), v.begin());
      return v;
    }
    if (H5Dread(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) < 0)
      fail(p, "cannot read samples (damaged or truncated file?): " + h5::last_error());
    return v;
  }

  Shot shot(hid_t shots, const std::string& name, bool load) const {
    const std::string p = "/shots/" + name;
    H5O_info_t info;
    if (H5Oget_info_by_name(shots, name.c_str(), &info, H5P_DEFAULT) < 0 ||
        info.type != H5O_TYPE_GROUP)
      fail(p, "not a group");
    h5::Id g = h5::group(H5Gopen2(shots, name.c_str(), H5P_DEFAULT));
    if (!g) fail(p, "cannot open group: " + h5::last_error());
    Shot s;
    s.name = name;
    auto rate = double_attr(g.get(), "sample_rate_hz", p);
    if (!rate) fail(p + "/sample_rate_hz", "missing required attribute");
    s.sample_rate_hz = *rate;
    if (!(s.sample_rate_hz > 0)) fail(p + "/sample_rate_hz", "must be positive");
    auto exc = string_attr(g.get(), "excitation", p);
    if (!exc) fail(p + "/excitation", "missing required attribute");
    auto e = parse_excitation(*exc);
    if (!e)
      fail(p + "/excitation",
           "unknown excitation '" + *exc + "' (exp_decay, sine, chirp, noise or arbitrary)");
    s.excitation = *e;
    s.amplitude_v = double_attr(g.get(), "amplitude_v", p);
    s.decay_per_s = double_attr(g.get(), "decay_per_s", p);
    s.frequency_hz = double_attr(g.get(), "frequency_hz", p);
    s.f_start_hz = double_attr(g.get(), "f_start_hz", p);
    s.f_stop_hz = double_attr(g.get(), "f_stop_hz", p);
    s.pretrigger_samples = int_attr(g.get(), "pretrigger_samples", p).value_or(0);
    if (auto r = string_attr(g.get(), "role", p)) {
      auto role = parse_role(*r);
      if (!role) fail(p + "/role", "unknown role '" + *r + "' (dut, open, short or load)");
      s.role = *role;
    }
    s.load_ohm = double_attr(g.get(), "load_ohm", p);
    s.load_parallel_f = double_attr(g.get(), "load_parallel_f", p);
    s.daq_range_v = double_attr(g.get(), "daq_range_v", p);
    s.v1_range_v = double_attr(g.get(), "v1_range_v", p);
    s.v2_range_v = double_attr(g.get(), "v2_range_v", p);
    s.adc_bits = int_attr(g.get(), "adc_bits", p);
    std::size_t n1 = 0, n2 = 0;
    signal(g.get(), "v1", p, false, &n1);  // shapes and attributes first: nothing allocated yet
    signal(g.get(), "v2", p, false, &n2);
    if (n1 != n2)
      fail(p, "length mismatch: v1 has " + std::to_string(n1) + " samples, v2 has " +
                  std::to_string(n2));
    if (n1 < kMinSamples)
      fail(p + "/v1", "too short: " + std::to_string(n1) + " samples, need at least " +
                          std::to_string(kMinSamples));
    validate_shot_attributes(s, n1, file_, p);
    if (budget_ && n1 > *budget_)
      fail(p, "implausible size: the capture's shots hold more than " +
                  std::to_string(kMaxCaptureSamples) + " samples per channel in all");
    if (budget_) *budget_ -= n1;
    if (load) {
      s.v1 = signal(g.get(), "v1", p, true, &n1);
      s.v2 = signal(g.get(), "v2", p, true, &n2);
      validate_shot(s, file_, p);
    }
    return s;
  }

 private:
  std::string file_;
  std::size_t* budget_ = nullptr;
};

herr_t collect_names(hid_t, const char* name, const H5L_info_t*, void* data) {
  static_cast<std::vector<std::string>*>(data)->emplace_back(name);
  return 0;
}

bool is_shot_name(const std::string& n) {
  return n.size() == 6 && std::all_of(n.begin(), n.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// ---------------------------------------------------------------- writing

void write_string_attr(hid_t obj, const char* name, const std::string& value) {
  h5::Id type = h5::datatype(H5Tcopy(H5T_C_S1));
  H5Tset_size(type.get(), H5T_VARIABLE);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  h5::Id space = h5::dataspace(H5Screate(H5S_SCALAR));
  h5::Id a = h5::attribute(H5Acreate2(obj, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT));
  const char* p = value.c_str();
  if (!a || H5Awrite(a.get(), type.get(), &p) < 0)
    throw std::runtime_error(std::string("HDF5: cannot write attribute ") + name + ": " +
                             h5::last_error());
}

void write_double_attr(hid_t obj, const char* name, double v) {
  h5::Id space = h5::dataspace(H5Screate(H5S_SCALAR));
  h5::Id a = h5::attribute(
      H5Acreate2(obj, name, H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (!a || H5Awrite(a.get(), H5T_NATIVE_DOUBLE, &v) < 0)
    throw std::runtime_error(std::string("HDF5: cannot write attribute ") + name + ": " +
                             h5::last_error());
}

void write_double_array_attr(hid_t obj, const char* name, const std::vector<double>& v) {
  const hsize_t n = v.size();
  h5::Id space = h5::dataspace(H5Screate_simple(1, &n, nullptr));
  h5::Id a = h5::attribute(
      H5Acreate2(obj, name, H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (!a || (n > 0 && H5Awrite(a.get(), H5T_NATIVE_DOUBLE, v.data()) < 0))
    throw std::runtime_error(std::string("HDF5: cannot write attribute ") + name + ": " +
                             h5::last_error());
}

void write_int_attr(hid_t obj, const char* name, std::int64_t v) {
  h5::Id space = h5::dataspace(H5Screate(H5S_SCALAR));
  h5::Id a =
      h5::attribute(H5Acreate2(obj, name, H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (!a || H5Awrite(a.get(), H5T_NATIVE_INT64, &v) < 0)
    throw std::runtime_error(std::string("HDF5: cannot write attribute ") + name + ": " +
                             h5::last_error());
}

void write_opt(hid_t obj, const char* name, const std::optional<double>& v) {
  if (v) write_double_attr(obj, name, *v);
}
void write_opt(hid_t obj, const char* name, const std::optional<std::string>& v) {
  if (v) write_string_attr(obj, name, *v);
}

void write_signal(hid_t grp, const char* name, const std::vector<double>& v, bool f32) {
  hsize_t n = v.size();
  h5::Id space = h5::dataspace(H5Screate_simple(1, &n, nullptr));
  h5::Id ds = h5::dataset(H5Dcreate2(grp, name, f32 ? H5T_IEEE_F32LE : H5T_IEEE_F64LE,
                                     space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!ds || H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) < 0)
    throw std::runtime_error(std::string("HDF5: cannot write dataset ") + name + ": " +
                             h5::last_error());
}

std::string utc_now_iso8601() {
  std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace

// ==================================================================== read

Capture read_capture(const fs::path& path, const ReadOptions& opt) {
  const std::string file = path.string();
  Reader rd(file);
  std::error_code ec;
  auto st = fs::status(path, ec);
  if (ec || !fs::exists(st)) rd.fail("/", "no such file");
  if (fs::is_directory(st)) rd.fail("/", "is a directory, not a capture file");
  if (!fs::is_regular_file(st)) rd.fail("/", "not a regular file");

  std::lock_guard lock(h5::h5_mutex());
  h5::quiet_errors();
  htri_t is = H5Fis_hdf5(file.c_str());
  if (is <= 0) {
    std::string why = h5::last_error();
    rd.fail("/", "not a readable HDF5 file" + (why.empty() ? std::string() : " (" + why + ")"));
  }
  h5::Id f = h5::file(H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  if (!f) rd.fail("/", "cannot open HDF5 file (damaged or truncated?): " + h5::last_error());

  Capture cap;
  cap.path = file;
  auto fmt = rd.string_attr(f.get(), "format", "/");
  if (!fmt) rd.fail("/format", "missing required attribute (expected \"piezo-capture\")");
  if (*fmt != kFormatName)
    rd.fail("/format", "is \"" + *fmt + "\", expected \"piezo-capture\"");
  auto ver = rd.int_attr(f.get(), "format_version", "/");
  if (!ver) rd.fail("/format_version", "missing required attribute");
  if (*ver != kFormatVersion)
    rd.fail("/format_version",
            "unsupported version " + std::to_string(*ver) + " (this reader knows version 1)");
  cap.created_utc = rd.string_attr(f.get(), "created_utc", "/");
  cap.software = rd.string_attr(f.get(), "software", "/");

  // /setup
  if (!rd.has_link(f.get(), "setup")) rd.fail("/setup", "missing required group");
  H5O_info_t info;
  if (H5Oget_info_by_name(f.get(), "setup", &info, H5P_DEFAULT) < 0 || info.type != H5O_TYPE_GROUP)
    rd.fail("/setup", "not a group");
  {
    h5::Id g = h5::group(H5Gopen2(f.get(), "setup", H5P_DEFAULT));
    if (!g) rd.fail("/setup", "cannot open group: " + h5::last_error());
    Setup& s = cap.setup;
    auto r1 = rd.double_attr(g.get(), "divider_r1_ohm", "/setup");
    if (!r1) rd.fail("/setup/divider_r1_ohm", "missing required attribute");
    s.divider_r1_ohm = *r1;
    s.transducer_id = rd.string_attr(g.get(), "transducer_id", "/setup");
    s.inner_diameter_m = rd.double_attr(g.get(), "inner_diameter_m", "/setup");
    s.outer_diameter_m = rd.double_attr(g.get(), "outer_diameter_m", "/setup");
    s.length_m = rd.double_attr(g.get(), "length_m", "/setup");
    s.density_kg_m3 = rd.double_attr(g.get(), "density_kg_m3", "/setup");
    s.material = rd.string_attr(g.get(), "material", "/setup");
    s.notes = rd.string_attr(g.get(), "notes", "/setup");
    try {  // not in piezo-capture/1: another writer's attribute of that name is ignored, never an error
      s.heldout_of = rd.string_attr(g.get(), "heldout_of", "/setup");
    } catch (const CaptureError&) {
      s.heldout_of.reset();
    }
    validate_setup(s, file);
  }

  // /shots
  if (!rd.has_link(f.get(), "shots")) rd.fail("/shots", "missing required group");
  if (H5Oget_info_by_name(f.get(), "shots", &info, H5P_DEFAULT) < 0 || info.type != H5O_TYPE_GROUP)
    rd.fail("/shots", "not a group");
  h5::Id shots = h5::group(H5Gopen2(f.get(), "shots", H5P_DEFAULT));
  if (!shots) rd.fail("/shots", "cannot open group: " + h5::last_error());
  std::vector<std::string> names;
  if (H5Literate(shots.get(), H5_INDEX_NAME, H5_ITER_INC, nullptr, collect_names, &names) < 0)
    rd.fail("/shots", "cannot list shots: " + h5::last_error());
  std::erase_if(names, [](const std::string& n) { return !is_shot_name(n); });  // others ignored
  if (names.empty()) rd.fail("/shots", "no shots (empty group)");
  std::sort(names.begin(), names.end());
  std::size_t budget = kMaxCaptureSamples;
  rd.limit_total(&budget);
  for (const auto& n : names) {
    try {
      cap.shots.push_back(rd.shot(shots.get(), n, opt.load_samples));
    } catch (const CaptureError& e) {
      if (!opt.skip_invalid_shots) throw;
      cap.rejected_shots.push_back(e.what());
    }
  }
  if (cap.shots.empty()) rd.fail("/shots", "no valid shot");
  return cap;
}

// =================================================================== write

fs::path partial_path_for(const fs::path& final_path) {
  fs::path p = final_path;
  p += ".partial";
  return p;
}

struct CaptureWriter::Impl {
  fs::path final_path, partial_path;
  h5::Id file;
  h5::Id shots;
  std::size_t count = 0;
  bool closed = false;

  void flush_to_disk() {
    if (H5Fflush(file.get(), H5F_SCOPE_GLOBAL) < 0)
      throw std::runtime_error("HDF5: cannot flush " + partial_path.string() + ": " +
                               h5::last_error());
    void* handle = nullptr;
    if (H5Fget_vfd_handle(file.get(), H5P_DEFAULT, &handle) >= 0 && handle)
      ::fsync(*static_cast<int*>(handle));
  }
};

CaptureWriter::CaptureWriter(fs::path final_path, const Setup& setup, const WriterOptions& opt)
    : impl_(std::make_unique<Impl>()) {
  impl_->final_path = std::move(final_path);
  impl_->partial_path = partial_path_for(impl_->final_path);
  const std::string fname = impl_->final_path.string();
  validate_setup(setup, fname);
  if (!opt.overwrite && fs::exists(impl_->final_path))
    throw CaptureError(fname, "/", "already exists (refusing to overwrite)");

  std::lock_guard lock(h5::h5_mutex());
  h5::quiet_errors();
  h5::Id fapl = h5::plist(H5Pcreate(H5P_FILE_ACCESS));
  // Oldest format the features need: files stay readable by older HDF5 / h5py.
  H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_EARLIEST, H5F_LIBVER_LATEST);
  impl_->file = h5::file(
      H5Fcreate(impl_->partial_path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()));
  if (!impl_->file)
    throw CaptureError(impl_->partial_path.string(), "/",
                       "cannot create file: " + h5::last_error());
  hid_t f = impl_->file.get();
  write_string_attr(f, "format", std::string(kFormatName));
  write_int_attr(f, "format_version", kFormatVersion);
  write_string_attr(f, "created_utc", utc_now_iso8601());
  write_string_attr(f, "software", opt.software.empty() ? "piezobench" : opt.software);

  h5::Id g = h5::group(H5Gcreate2(f, "setup", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  write_double_attr(g.get(), "divider_r1_ohm", setup.divider_r1_ohm);
  write_opt(g.get(), "transducer_id", setup.transducer_id);
  write_opt(g.get(), "inner_diameter_m", setup.inner_diameter_m);
  write_opt(g.get(), "outer_diameter_m", setup.outer_diameter_m);
  write_opt(g.get(), "length_m", setup.length_m);
  write_opt(g.get(), "density_kg_m3", setup.density_kg_m3);
  write_opt(g.get(), "material", setup.material);
  write_opt(g.get(), "notes", setup.notes);
  write_opt(g.get(), "heldout_of", setup.heldout_of);
  impl_->shots = h5::group(H5Gcreate2(f, "shots", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!impl_->shots) throw std::runtime_error("HDF5: cannot create /shots: " + h5::last_error());
  impl_->flush_to_disk();
}

CaptureWriter::~CaptureWriter() {
  if (impl_ && !impl_->closed) {
    try {
      close();
    } catch (...) {
      // Nothing more can be done here; the .partial file still holds every flushed shot.
    }
  }
}

std::string CaptureWriter::append(const Shot& shot) {
  if (impl_->closed) throw std::logic_error("CaptureWriter::append: writer is closed");
  char name[16];
  std::snprintf(name, sizeof name, "%06zu", impl_->count);
  validate_shot(shot, impl_->final_path.string(), std::string("/shots/") + name);

  std::lock_guard lock(h5::h5_mutex());
  // Build the shot as an anonymous group and link it under /shots only when
  // complete: a crash mid-shot never leaves a half shot under a shot name.
  h5::Id g = h5::group(H5Gcreate_anon(impl_->file.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (!g) throw std::runtime_error("HDF5: cannot create shot group: " + h5::last_error());
  hid_t gid = g.get();
  write_double_attr(gid, "sample_rate_hz", shot.sample_rate_hz);
  write_string_attr(gid, "excitation", std::string(to_string(shot.excitation)));
  write_opt(gid, "amplitude_v", shot.amplitude_v);
  write_opt(gid, "decay_per_s", shot.decay_per_s);
  write_opt(gid, "frequency_hz", shot.frequency_hz);
  write_opt(gid, "f_start_hz", shot.f_start_hz);
  write_opt(gid, "f_stop_hz", shot.f_stop_hz);
  write_int_attr(gid, "pretrigger_samples", shot.pretrigger_samples);
  write_string_attr(gid, "role", std::string(to_string(shot.role)));
  write_opt(gid, "load_ohm", shot.load_ohm);
  write_opt(gid, "load_parallel_f", shot.load_parallel_f);
  write_opt(gid, "daq_range_v", shot.daq_range_v);
  write_opt(gid, "v1_range_v", shot.v1_range_v);
  write_opt(gid, "v2_range_v", shot.v2_range_v);
  if (shot.adc_bits) write_int_attr(gid, "adc_bits", *shot.adc_bits);
  write_signal(gid, "v1", shot.v1, shot.store_float32);
  write_signal(gid, "v2", shot.v2, shot.store_float32);
  if (H5Olink(gid, impl_->shots.get(), name, H5P_DEFAULT, H5P_DEFAULT) < 0)
    throw std::runtime_error(std::string("HDF5: cannot link shot ") + name + ": " +
                             h5::last_error());
  g.reset();
  impl_->flush_to_disk();
  ++impl_->count;
  return name;
}

void CaptureWriter::write_truth(
    const std::vector<std::pair<std::string, double>>& numbers,
    const std::vector<std::pair<std::string, std::string>>& strings,
    const std::vector<std::pair<std::string, std::vector<double>>>& series) {
  if (impl_->closed) throw std::logic_error("CaptureWriter::write_truth: writer is closed");
  std::lock_guard lock(h5::h5_mutex());
  hid_t f = impl_->file.get();
  h5::Id g = h5::group(H5Lexists(f, "truth", H5P_DEFAULT) > 0
                           ? H5Gopen2(f, "truth", H5P_DEFAULT)
                           : H5Gcreate2(f, "truth", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!g) throw std::runtime_error("HDF5: cannot create /truth: " + h5::last_error());
  for (const auto& [k, v] : numbers) {
    if (H5Aexists(g.get(), k.c_str()) > 0) H5Adelete(g.get(), k.c_str());
    write_double_attr(g.get(), k.c_str(), v);
  }
  for (const auto& [k, v] : strings) {
    if (H5Aexists(g.get(), k.c_str()) > 0) H5Adelete(g.get(), k.c_str());
    write_string_attr(g.get(), k.c_str(), v);
  }
  for (const auto& [k, v] : series) {
    if (H5Aexists(g.get(), k.c_str()) > 0) H5Adelete(g.get(), k.c_str());
    write_double_array_attr(g.get(), k.c_str(), v);
  }
  g.reset();
  impl_->flush_to_disk();
}

void CaptureWriter::close() {
  if (impl_->closed) return;
  impl_->closed = true;
  {
    std::lock_guard lock(h5::h5_mutex());
    impl_->shots.reset();
    impl_->flush_to_disk();
    impl_->file.reset();
  }
  std::error_code ec;
  fs::rename(impl_->partial_path, impl_->final_path, ec);
  if (ec)
    throw CaptureError(impl_->final_path.string(), "/",
                       "cannot rename " + impl_->partial_path.string() + ": " + ec.message() +
                           " (the data are in the .partial file)");
}

std::size_t CaptureWriter::shots_written() const { return impl_->count; }
const fs::path& CaptureWriter::final_path() const { return impl_->final_path; }
const fs::path& CaptureWriter::partial_path() const { return impl_->partial_path; }

void write_capture(const fs::path& file, const Capture& cap, const WriterOptions& opt) {
  WriterOptions o = opt;
  if (o.software.empty() && cap.software) o.software = *cap.software;
  CaptureWriter w(file, cap.setup, o);
  for (const auto& s : cap.shots) w.append(s);
  w.close();
}

}  // namespace piezo::acq
