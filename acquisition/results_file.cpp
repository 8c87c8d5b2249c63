// piezo-replay/1 results files through the HDF5 C library (see results_file.hpp).
// Every call runs under the project's HDF5 lock: replay workers are threads.
#include "acquisition/results_file.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <optional>

#include "acquisition/h5_handle.hpp"

namespace piezo::acq {

namespace fs = std::filesystem;

namespace {

[[noreturn]] void fail(const std::string& file, const std::string& where,
                       const std::string& problem) {
  throw ResultsError(file + ": " + where + ": " + problem);
}

std::string utc_now() {
  std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

h5::Id vlen_string_type() {
  h5::Id type = h5::datatype(H5Tcopy(H5T_C_S1));
  H5Tset_size(type.get(), H5T_VARIABLE);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  return type;
}

void write_string_attr(hid_t obj, const char* name, const std::string& value) {
  h5::Id type = vlen_string_type();
  h5::Id space = h5::dataspace(H5Screate(H5S_SCALAR));
  h5::Id a =
      h5::attribute(H5Acreate2(obj, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT));
  const char* p = value.c_str();
  if (!a || H5Awrite(a.get(), type.get(), &p) < 0)
    throw std::runtime_error(std::string("HDF5: cannot write attribute ") + name + ": " +
                             h5::last_error());
}

void write_number_attr(hid_t obj, const char* name, hid_t file_type, hid_t mem_type,
                       const void* v) {
  h5::Id space = h5::dataspace(H5Screate(H5S_SCALAR));
  h5::Id a = h5::attribute(H5Acreate2(obj, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (!a || H5Awrite(a.get(), mem_type, v) < 0)
    throw std::runtime_error(std::string("HDF5: cannot write attribute ") + name + ": " +
                             h5::last_error());
}

void write_string_dataset(hid_t grp, const char* name, const std::string& value) {
  h5::Id type = vlen_string_type();
  h5::Id space = h5::dataspace(H5Screate(H5S_SCALAR));
  h5::Id ds = h5::dataset(
      H5Dcreate2(grp, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  const char* p = value.c_str();
  if (!ds || H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &p) < 0)
    throw std::runtime_error(std::string("HDF5: cannot write dataset ") + name + ": " +
                             h5::last_error());
}

void write_doubles(hid_t grp, const char* name, const double* v, int rank, const hsize_t* dims) {
  h5::Id space = h5::dataspace(H5Screate_simple(rank, dims, nullptr));
  h5::Id ds = h5::dataset(
      H5Dcreate2(grp, name, H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!ds || H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) < 0)
    throw std::runtime_error(std::string("HDF5: cannot write dataset ") + name + ": " +
                             h5::last_error());
}

bool valid_key(const std::string& k) {
  return !k.empty() && k.size() <= 128 && std::all_of(k.begin(), k.end(), [](char c) {
    return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' ||
           c == '-';
  });
}

// ---------------------------------------------------------------- reading

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}
  [[noreturn]] void fail(const std::string& where, const std::string& problem) const {
    acq::fail(file_, where, problem);
  }

  std::optional<std::string> string_attr(hid_t obj, const char* name,
                                         const std::string& where) const {
    if (H5Aexists(obj, name) <= 0) return std::nullopt;
    h5::Id a = h5::attribute(H5Aopen(obj, name, H5P_DEFAULT));
    h5::Id type = h5::datatype(H5Aget_type(a.get()));
    if (!a || H5Tget_class(type.get()) != H5T_STRING)
      fail(where + "/" + name, "expected a string attribute");
    return read_string(a.get(), type.get(), true, where + "/" + name);
  }

  std::optional<double> double_attr(hid_t obj, const char* name, const std::string& where) const {
    if (H5Aexists(obj, name) <= 0) return std::nullopt;
    h5::Id a = h5::attribute(H5Aopen(obj, name, H5P_DEFAULT));
    double v = 0;
    if (!a || H5Aread(a.get(), H5T_NATIVE_DOUBLE, &v) < 0)
      fail(where + "/" + name, "expected a number");
    return v;
  }

  std::optional<std::int64_t> int_attr(hid_t obj, const char* name,
                                       const std::string& where) const {
    if (H5Aexists(obj, name) <= 0) return std::nullopt;
    h5::Id a = h5::attribute(H5Aopen(obj, name, H5P_DEFAULT));
    h5::Id type = h5::datatype(H5Aget_type(a.get()));
    std::int64_t v = 0;
    if (!a || H5Tget_class(type.get()) != H5T_INTEGER || H5Aread(a.get(), H5T_NATIVE_INT64, &v) < 0)
      fail(where + "/" + name, "expected an integer");
    return v;
  }

  std::string string_dataset(hid_t grp, const char* name, const std::string& where) const {
    const std::string p = where + "/" + name;
    if (H5Lexists(grp, name, H5P_DEFAULT) <= 0) fail(p, "missing dataset");
    h5::Id ds = h5::dataset(H5Dopen2(grp, name, H5P_DEFAULT));
    if (!ds) fail(p, "cannot open dataset: " + h5::last_error());
    h5::Id type = h5::datatype(H5Dget_type(ds.get()));
    if (H5Tget_class(type.get()) != H5T_STRING) fail(p, "expected a string dataset");
    return read_string(ds.get(), type.get(), false, p);
  }

  std::vector<double> doubles(hid_t grp, const char* name, const std::string& where, hsize_t cols,
                              hsize_t* rows) const {
    const std::string p = where + "/" + name;
    h5::Id ds = h5::dataset(H5Dopen2(grp, name, H5P_DEFAULT));
    if (!ds) fail(p, "missing dataset");
    h5::Id space = h5::dataspace(H5Dget_space(ds.get()));
    hsize_t dims[2] = {0, 0};
    const int rank = H5Sget_simple_extent_ndims(space.get());
    if (rank != (cols == 1 ? 1 : 2)) fail(p, "wrong shape");
    H5Sget_simple_extent_dims(space.get(), dims, nullptr);
    if (cols != 1 && dims[1] != cols) fail(p, "wrong shape");
    *rows = dims[0];
    std::vector<double> v(dims[0] * cols);
    if (!v.empty() &&
        H5Dread(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) < 0)
      fail(p, "cannot read (damaged file?): " + h5::last_error());
    return v;
  }

  ResultsFile::IndexEntry entry(hid_t results, const std::string& key) const {
    const std::string p = "/results/" + key;
    h5::Id g = h5::group(H5Gopen2(results, key.c_str(), H5P_DEFAULT));
    if (!g) fail(p, "not a group");
    auto need = [&](const char* name) {
      auto v = string_attr(g.get(), name, p);
      if (!v) fail(p + "/" + name, "missing required attribute");
      return *v;
    };
    return {key, need("input_path"), need("sha256"), need("status")};
  }

  ResultRecord record(hid_t results, const std::string& key, bool curves) const {
    const std::string p = "/results/" + key;
    h5::Id g = h5::group(H5Gopen2(results, key.c_str(), H5P_DEFAULT));
    if (!g) fail(p, "not a group");
    ResultRecord r;
    r.key = key;
    auto need = [&](const char* name) {
      auto v = string_attr(g.get(), name, p);
      if (!v) fail(p + "/" + name, "missing required attribute");
      return *v;
    };
    r.input_path = need("input_path");
    r.sha256 = need("sha256");
    r.status = need("status");
    r.replayed_utc = string_attr(g.get(), "replayed_utc", p).value_or("");
    r.elapsed_s = double_attr(g.get(), "elapsed_s", p).value_or(0.0);
    r.result_json = string_dataset(g.get(), "result_json", p);
    if (curves && H5Lexists(g.get(), "curves", H5P_DEFAULT) > 0) {
      h5::Id cg = h5::group(H5Gopen2(g.get(), "curves", H5P_DEFAULT));
      for (const auto& name : names(cg.get(), p + "/curves")) {
        const std::string cp = p + "/curves/" + name;
        h5::Id c = h5::group(H5Gopen2(cg.get(), name.c_str(), H5P_DEFAULT));
        if (!c) fail(cp, "not a group");
        StoredCurve sc;
        sc.label = string_attr(c.get(), "label", cp).value_or("");
        hsize_t nf = 0, nz = 0;
        sc.f_hz = doubles(c.get(), "f_hz", cp, 1, &nf);
        auto z = doubles(c.get(), "z_ohm", cp, 2, &nz);
        if (nf != nz) fail(cp, "f_hz and z_ohm differ in length");
        sc.z_ohm.resize(nz);
        for (hsize_t i = 0; i < nz; ++i) sc.z_ohm[i] = {z[2 * i], z[2 * i + 1]};
        r.curves.push_back(std::move(sc));
      }
    }
    return r;
  }

  std::vector<std::string> names(hid_t grp, const std::string& where) const {
    std::vector<std::string> out;
    auto cb = [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
      static_cast<std::vector<std::string>*>(data)->emplace_back(name);
      return 0;
    };
    if (H5Literate(grp, H5_INDEX_NAME, H5_ITER_INC, nullptr, cb, &out) < 0)
      fail(where, "cannot list members: " + h5::last_error());
    std::sort(out.begin(), out.end());
    return out;
  }

  // Root attributes: the format and its version.
  void check_format(hid_t f) const {
    auto fmt = string_attr(f, "format", "");
    if (!fmt) fail("/format", "missing: not a piezo-replay results file");
    if (*fmt != kResultsFormatName)
      fail("/format", "is \"" + *fmt + "\", expected \"" + std::string(kResultsFormatName) + "\"");
    auto ver = int_attr(f, "format_version", "");
    if (!ver || *ver != kResultsFormatVersion)
      fail("/format_version",
           "unsupported (this reader knows version " + std::to_string(kResultsFormatVersion) + ")");
    if (H5Lexists(f, "results", H5P_DEFAULT) <= 0) fail("/results", "missing required group");
  }

 private:
  std::string read_string(hid_t obj, hid_t type, bool attr, const std::string& where) const {
    if (H5Tis_variable_str(type) > 0) {
      h5::Id mem = vlen_string_type();
      char* p = nullptr;
      herr_t rc = attr ? H5Aread(obj, mem.get(), &p)
                       : H5Dread(obj, mem.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &p);
      if (rc < 0) fail(where, "cannot read string: " + h5::last_error());
      std::string out = p ? p : "";
      if (p) H5free_memory(p);
      return out;
    }
    std::string buf(H5Tget_size(type), '\0');
    h5::Id mem = h5::datatype(H5Tcopy(type));
    herr_t rc = attr ? H5Aread(obj, mem.get(), buf.data())
                     : H5Dread(obj, mem.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
    if (rc < 0) fail(where, "cannot read string: " + h5::last_error());
    return buf.substr(0, buf.find('\0'));
  }

  std::string file_;
};

h5::Id open_existing(const std::string& file, unsigned flags) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec))
    fail(file, "/", fs::exists(file, ec) ? "not a regular file" : "no such file");
  h5::quiet_errors();
  if (H5Fis_hdf5(file.c_str()) <= 0) fail(file, "/", "not a readable HDF5 file");
  h5::Id f = h5::file(H5Fopen(file.c_str(), flags, H5P_DEFAULT));
  if (!f) {
    const std::string why = h5::last_error();
    if (why.find("lock") != std::string::npos)  // HDF5's file locking: a writer holds the file
      fail(file, "/", "in use by another process (another replay writing it?): " + why);
    fail(file, "/", "cannot open (damaged file?): " + why);
  }
  return f;
}

}  // namespace

void for_each_result(const fs::path& path, const std::function<void(const ResultRecord&)>& fn,
                     const ResultsReadOptions& opt) {
  const std::string file = path.string();
  Reader rd(file);
  std::vector<std::string> keys;
  h5::Id f, results;
  // Ids are closed under the lock too: HDF5 is not thread-safe.
  struct Closer {
    h5::Id &f, &results;
    ~Closer() {
      std::lock_guard lock(h5::h5_mutex());
      results.reset();
      f.reset();
    }
  } closer{f, results};
  {
    std::lock_guard lock(h5::h5_mutex());
    f = open_existing(file, H5F_ACC_RDONLY);
    rd.check_format(f.get());
    results = h5::group(H5Gopen2(f.get(), "results", H5P_DEFAULT));
    if (!results) rd.fail("/results", "not a group");
    keys = rd.names(results.get(), "/results");
  }
  std::erase_if(keys,
                [](const std::string& k) { return !valid_key(k); });  // e.g. a merge's ".incoming"
  // One record in memory at a time; the lock is released while `fn` runs.
  for (const auto& key : keys) {
    ResultRecord r;
    {
      std::lock_guard lock(h5::h5_mutex());
      r = rd.record(results.get(), key, opt.load_curves);
    }
    fn(r);
  }
}

// =================================================================== writing

struct ResultsFile::Impl {
  fs::path path;
  h5::Id file, results;

  void flush_to_disk() {
    if (H5Fflush(file.get(), H5F_SCOPE_GLOBAL) < 0)
      throw std::runtime_error("HDF5: cannot flush " + path.string() + ": " + h5::last_error());
    void* handle = nullptr;
    if (H5Fget_vfd_handle(file.get(), H5P_DEFAULT, &handle) >= 0 && handle)
      ::fsync(*static_cast<int*>(handle));
  }

  // Replaces `key` by the complete anonymous group `g` in one step.
  void link(hid_t g, const std::string& key) {
    if (H5Lexists(results.get(), key.c_str(), H5P_DEFAULT) > 0 &&
        H5Ldelete(results.get(), key.c_str(), H5P_DEFAULT) < 0)
      throw std::runtime_error("HDF5: cannot replace record " + key + ": " + h5::last_error());
    if (H5Olink(g, results.get(), key.c_str(), H5P_DEFAULT, H5P_DEFAULT) < 0)
      throw std::runtime_error("HDF5: cannot link record " + key + ": " + h5::last_error());
  }
};

ResultsFile::ResultsFile(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ResultsFile::ResultsFile(ResultsFile&&) noexcept = default;
ResultsFile& ResultsFile::operator=(ResultsFile&&) noexcept = default;
ResultsFile::~ResultsFile() {
  try {
    close();
  } catch (...) {
    // Every record was flushed when it was written; nothing more to save.
  }
}

ResultsFile ResultsFile::create(const fs::path& path, const std::string& software) {
  const std::string file = path.string();
  std::error_code ec;
  if (fs::exists(path, ec)) fail(file, "/", "already exists (refusing to overwrite)");
  std::lock_guard lock(h5::h5_mutex());
  h5::quiet_errors();
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  h5::Id fapl = h5::plist(H5Pcreate(H5P_FILE_ACCESS));
  // The oldest format: no superblock "open for writing" flag survives a kill,
  // and older HDF5 / h5py read the file.
  H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_EARLIEST, H5F_LIBVER_LATEST);
  impl->file = h5::file(H5Fcreate(file.c_str(), H5F_ACC_EXCL, H5P_DEFAULT, fapl.get()));
  if (!impl->file) fail(file, "/", "cannot create file: " + h5::last_error());
  hid_t f = impl->file.get();
  write_string_attr(f, "format", std::string(kResultsFormatName));
  write_number_attr(f, "format_version", H5T_STD_I64LE, H5T_NATIVE_INT64, &kResultsFormatVersion);
  write_string_attr(f, "software", software);
  write_string_attr(f, "created_utc", utc_now());
  impl->results = h5::group(H5Gcreate2(f, "results", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!impl->results) throw std::runtime_error("HDF5: cannot create /results: " + h5::last_error());
  impl->flush_to_disk();
  return ResultsFile(std::move(impl));
}

ResultsFile ResultsFile::open_or_create(const fs::path& path, const std::string& software) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return create(path, software);
  const std::string file = path.string();
  std::lock_guard lock(h5::h5_mutex());
  // Check read-only first: a file of another kind is never opened for writing.
  Reader(file).check_format(open_existing(file, H5F_ACC_RDONLY).get());
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->file = open_existing(file, H5F_ACC_RDWR);
  impl->results = h5::group(H5Gopen2(impl->file.get(), "results", H5P_DEFAULT));
  if (!impl->results) fail(file, "/results", "not a group");
  return ResultsFile(std::move(impl));
}

void ResultsFile::put(const ResultRecord& rec) {
  if (!impl_ || !impl_->file) throw std::logic_error("ResultsFile::put: file is closed");
  if (!valid_key(rec.key))
    throw std::invalid_argument("ResultsFile::put: bad key '" + rec.key + "'");
  std::lock_guard lock(h5::h5_mutex());
  h5::Id g = h5::group(H5Gcreate_anon(impl_->file.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (!g) throw std::runtime_error("HDF5: cannot create a record group: " + h5::last_error());
  write_string_attr(g.get(), "input_path", rec.input_path);
  write_string_attr(g.get(), "sha256", rec.sha256);
  write_string_attr(g.get(), "status", rec.status);
  write_string_attr(g.get(), "replayed_utc",
                    rec.replayed_utc.empty() ? utc_now() : rec.replayed_utc);
  write_number_attr(g.get(), "elapsed_s", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &rec.elapsed_s);
  write_string_dataset(g.get(), "result_json", rec.result_json);
  if (!rec.curves.empty()) {
    h5::Id cg = h5::group(H5Gcreate2(g.get(), "curves", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    for (std::size_t k = 0; k < rec.curves.size(); ++k) {
      const auto& c = rec.curves[k];
      if (c.f_hz.size() != c.z_ohm.size())
        throw std::invalid_argument("ResultsFile::put: curve sizes differ");
      char name[32];
      std::snprintf(name, sizeof name, "%02zu", k);
      h5::Id cgrp = h5::group(H5Gcreate2(cg.get(), name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
      write_string_attr(cgrp.get(), "label", c.label);
      hsize_t n = c.f_hz.size();
      write_doubles(cgrp.get(), "f_hz", c.f_hz.data(), 1, &n);
      const hsize_t dims[2] = {n, 2};
      // std::complex<double> is laid out as double[2] (re, im).
      write_doubles(cgrp.get(), "z_ohm", reinterpret_cast<const double*>(c.z_ohm.data()), 2, dims);
    }
  }
  impl_->link(g.get(), rec.key);
  g.reset();
  impl_->flush_to_disk();
}

std::vector<ResultsFile::IndexEntry> ResultsFile::index() const {
  if (!impl_ || !impl_->file) throw std::logic_error("ResultsFile::index: file is closed");
  std::lock_guard lock(h5::h5_mutex());
  Reader rd(impl_->path.string());
  std::vector<IndexEntry> out;
  for (const auto& key : rd.names(impl_->results.get(), "/results"))
    if (valid_key(key)) out.push_back(rd.entry(impl_->results.get(), key));
  return out;
}

std::optional<ResultRecord> ResultsFile::get(const std::string& key,
                                             const ResultsReadOptions& opt) const {
  if (!impl_ || !impl_->file) throw std::logic_error("ResultsFile::get: file is closed");
  std::lock_guard lock(h5::h5_mutex());
  if (!valid_key(key) || H5Lexists(impl_->results.get(), key.c_str(), H5P_DEFAULT) <= 0)
    return std::nullopt;
  return Reader(impl_->path.string()).record(impl_->results.get(), key, opt.load_curves);
}

void ResultsFile::remove(const std::string& key) {
  if (!impl_ || !impl_->file) throw std::logic_error("ResultsFile::remove: file is closed");
  std::lock_guard lock(h5::h5_mutex());
  if (!valid_key(key) || H5Lexists(impl_->results.get(), key.c_str(), H5P_DEFAULT) <= 0) return;
  if (H5Ldelete(impl_->results.get(), key.c_str(), H5P_DEFAULT) < 0)
    throw std::runtime_error("HDF5: cannot remove record " + key + ": " + h5::last_error());
  impl_->flush_to_disk();
}

void ResultsFile::copy_from(const fs::path& src, const std::vector<std::string>& keys) {
  if (!impl_ || !impl_->file) throw std::logic_error("ResultsFile::copy_from: file is closed");
  const std::string file = src.string();
  std::lock_guard lock(h5::h5_mutex());
  h5::Id f = open_existing(file, H5F_ACC_RDONLY);
  Reader rd(file);
  rd.check_format(f.get());
  h5::Id results = h5::group(H5Gopen2(f.get(), "results", H5P_DEFAULT));
  for (const auto& key : keys) {
    if (!valid_key(key) || H5Lexists(results.get(), key.c_str(), H5P_DEFAULT) <= 0)
      rd.fail("/results/" + key, "no such record");
    // Copy under a temporary name, then swap it in: the key never names a half copy.
    const std::string tmp = ".incoming";
    if (H5Lexists(impl_->results.get(), tmp.c_str(), H5P_DEFAULT) > 0)
      H5Ldelete(impl_->results.get(), tmp.c_str(), H5P_DEFAULT);
    if (H5Ocopy(results.get(), key.c_str(), impl_->results.get(), tmp.c_str(), H5P_DEFAULT,
                H5P_DEFAULT) < 0)
      rd.fail("/results/" + key, "cannot copy: " + h5::last_error());
    if (H5Lexists(impl_->results.get(), key.c_str(), H5P_DEFAULT) > 0)
      H5Ldelete(impl_->results.get(), key.c_str(), H5P_DEFAULT);
    if (H5Lmove(impl_->results.get(), tmp.c_str(), impl_->results.get(), key.c_str(), H5P_DEFAULT,
                H5P_DEFAULT) < 0)
      throw std::runtime_error("HDF5: cannot link record " + key + ": " + h5::last_error());
  }
  impl_->flush_to_disk();
}

void ResultsFile::close() {
  if (!impl_ || !impl_->file) return;
  std::lock_guard lock(h5::h5_mutex());
  impl_->results.reset();
  struct Reset {
    h5::Id& f;
    ~Reset() { f.reset(); }
  } reset{impl_->file};  // closed even when the flush fails
  impl_->flush_to_disk();
}

const fs::path& ResultsFile::path() const { return impl_->path; }

}  // namespace piezo::acq
