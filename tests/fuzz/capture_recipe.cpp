// Fuzz bytes -> a piezo-capture/1 file written through the HDF5 C API, and
// what capture-format.md makes of it. See capture_recipe.hpp.
#include "tests/fuzz/capture_recipe.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <utility>

namespace piezo::fuzz {

namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// HDF5 refused a step of the recipe: no file, no finding.
struct Refused {};

class Id {
 public:
  using Closer = herr_t (*)(hid_t);
  Id(hid_t id, Closer c) : id_(id), close_(c) {
    if (id_ < 0) throw Refused{};
  }
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  ~Id() { close_(id_); }
  hid_t get() const { return id_; }
  operator hid_t() const { return id_; }

 private:
  hid_t id_;
  Closer close_;
};

void ok(herr_t e) {
  if (e < 0) throw Refused{};
}

// ------------------------------------------------------------ values
// A value for a numeric attribute whose ordinary value is `typical`.
double pick_value(ByteReader& r, double typical) {
  switch (r.pick(24)) {
    case 12: return typical * (0.5 + r.u8() / 128.0);
    case 13: return 0.0;
    case 14: return -typical;
    case 15: return kNaN;
    case 16: return kInf;
    case 17: return -kInf;
    case 18: return 1e308;
    case 19: return 4.9e-324;  // smallest subnormal
    case 20: return r.raw_double();
    case 21: return -0.0;
    case 22: return 1e-300;
    case 23: return typical * 1e6;
    default: return typical;
  }
}

float to_float(double v) {  // IEEE conversion without the UB of an out-of-range cast
  if (std::isfinite(v) && std::abs(v) > static_cast<double>(FLT_MAX))
    return v > 0 ? std::numeric_limits<float>::infinity() : -std::numeric_limits<float>::infinity();
  return static_cast<float>(v);
}

template <class I>
I saturate(double v) {
  if (std::isnan(v)) return 0;
  if (v <= static_cast<double>(std::numeric_limits<I>::min())) return std::numeric_limits<I>::min();
  if (v >= static_cast<double>(std::numeric_limits<I>::max())) return std::numeric_limits<I>::max();
  return static_cast<I>(v);
}

// ------------------------------------------------------------ attributes
enum class Shape { Scalar, One, Two, Zero, Null };

Shape pick_shape(ByteReader& r) {
  switch (r.pick(32)) {
    case 28: return Shape::One;
    case 29: return Shape::Two;
    case 30: return Shape::Zero;
    case 31: return Shape::Null;
    default: return Shape::Scalar;
  }
}

hid_t make_space(Shape s) {
  hsize_t one = 1, two = 2, zero = 0;
  switch (s) {
    case Shape::Scalar: return H5Screate(H5S_SCALAR);
    case Shape::One: return H5Screate_simple(1, &one, nullptr);
    case Shape::Two: return H5Screate_simple(1, &two, nullptr);
    case Shape::Zero: return H5Screate_simple(1, &zero, nullptr);
    case Shape::Null: return H5Screate(H5S_NULL);
  }
  return -1;
}

std::size_t points(Shape s) { return s == Shape::Two ? 2 : (s == Shape::Scalar || s == Shape::One) ? 1 : 0; }

// Writes `n` copies of the element at `mem` (memory type `mt`) as attribute `name`.
void put_attr(hid_t loc, const char* name, hid_t file_type, hid_t mem_type, Shape shape, const void* elem,
              std::size_t elem_size) {
  Id space(make_space(shape), H5Sclose);
  Id a(H5Acreate2(loc, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  const std::size_t n = points(shape);
  if (n == 0) return;
  std::vector<unsigned char> buf(n * elem_size);
  for (std::size_t i = 0; i < n; ++i) std::memcpy(buf.data() + i * elem_size, elem, elem_size);
  ok(H5Awrite(a, mem_type, buf.data()));
}

void put_vlen_string(hid_t loc, const char* name, const std::string& v, H5T_cset_t cset, Shape shape) {
  Id t(H5Tcopy(H5T_C_S1), H5Tclose);
  ok(H5Tset_size(t, H5T_VARIABLE));
  ok(H5Tset_cset(t, cset));
  const char* p = v.c_str();
  put_attr(loc, name, t, t, shape, &p, sizeof p);
}

void put_fixed_string(hid_t loc, const char* name, const std::string& v, H5T_str_t pad, std::size_t extra) {
  Id t(H5Tcopy(H5T_C_S1), H5Tclose);
  const std::size_t size = v.size() + extra + (pad == H5T_STR_NULLTERM ? 1 : 0);
  ok(H5Tset_size(t, std::max<std::size_t>(size, 1)));
  ok(H5Tset_strpad(t, pad));
  std::string buf = v;
  buf.resize(std::max<std::size_t>(size, 1), pad == H5T_STR_SPACEPAD ? ' ' : '\0');
  put_attr(loc, name, t, t, Shape::Scalar, buf.data(), buf.size());
}

// A number attribute. `value`: what a correct reader gets (unset when the
// type or shape leaves nothing to read); `verdict`: of the type and shape alone.
struct Num {
  bool present = false;
  Verdict verdict = Verdict::Valid;
  std::optional<double> value;
};

Num num_attr(ByteReader& r, hid_t loc, const char* name, double typical, std::string& notes) {
  Num out;
  if (r.pick(10) == 9) return out;  // absent
  out.present = true;
  const double v = pick_value(r, typical);
  const Shape shape = pick_shape(r);
  const bool readable = shape == Shape::Scalar || shape == Shape::One;
  out.verdict = shape == Shape::Scalar ? Verdict::Valid : Verdict::Unknown;
  char note[96];
  const unsigned kind = static_cast<unsigned>(r.pick(32));
  std::snprintf(note, sizeof note, " %s=%g(t%u,s%d)", name, v, kind, static_cast<int>(shape));
  notes += note;
  if (kind < 24 || kind == 24) {  // float64, little or big endian
    put_attr(loc, name, kind < 24 ? H5T_IEEE_F64LE : H5T_IEEE_F64BE, H5T_NATIVE_DOUBLE, shape, &v, sizeof v);
    if (readable) out.value = v;
  } else if (kind == 25 || kind == 26) {  // float32: the format says float64
    const float f = to_float(v);
    put_attr(loc, name, kind == 25 ? H5T_IEEE_F32LE : H5T_IEEE_F32BE, H5T_NATIVE_FLOAT, shape, &f, sizeof f);
    out.verdict = Verdict::Unknown;
    if (readable) out.value = f;
  } else if (kind == 27) {
    const std::int32_t i = saturate<std::int32_t>(v);
    put_attr(loc, name, H5T_STD_I32LE, H5T_NATIVE_INT32, shape, &i, sizeof i);
    out.verdict = Verdict::Unknown;
    if (readable) out.value = i;
  } else if (kind == 28) {
    const std::int64_t i = saturate<std::int64_t>(v);
    put_attr(loc, name, H5T_STD_I64BE, H5T_NATIVE_INT64, shape, &i, sizeof i);
    out.verdict = Verdict::Unknown;
    if (readable) out.value = static_cast<double>(i);
  } else if (kind == 29) {
    const std::uint64_t u = saturate<std::uint64_t>(v);
    put_attr(loc, name, H5T_STD_U64LE, H5T_NATIVE_UINT64, shape, &u, sizeof u);
    out.verdict = Verdict::Unknown;
    if (readable) out.value = static_cast<double>(u);
  } else if (kind == 30) {  // a string where a number belongs: wrong type
    put_vlen_string(loc, name, std::to_string(v), H5T_CSET_UTF8, shape);
    out.verdict = Verdict::Invalid;
  } else {  // a compound {double}: wrong type
    Id t(H5Tcreate(H5T_COMPOUND, sizeof(double)), H5Tclose);
    ok(H5Tinsert(t, "value", 0, H5T_NATIVE_DOUBLE));
    put_attr(loc, name, t, t, shape, &v, sizeof v);
    out.verdict = Verdict::Invalid;
  }
  return out;
}

// An integer attribute (format_version, pretrigger_samples). `int64_valid`:
// the format names int64 exactly (otherwise any integer type is "int").
struct Int {
  bool present = false;
  Verdict verdict = Verdict::Valid;
  std::optional<std::int64_t> value;
};

Int int_attr(ByteReader& r, hid_t loc, const char* name, std::int64_t v, bool int64_only, std::string& notes) {
  Int out;
  out.present = true;
  const Shape shape = pick_shape(r);
  const bool readable = shape == Shape::Scalar || shape == Shape::One;
  out.verdict = shape == Shape::Scalar ? Verdict::Valid : Verdict::Unknown;
  const unsigned kind = static_cast<unsigned>(r.pick(16));
  char note[96];
  std::snprintf(note, sizeof note, " %s=%lld(t%u,s%d)", name, static_cast<long long>(v), kind,
                static_cast<int>(shape));
  notes += note;
  if (kind < 11) {
    put_attr(loc, name, H5T_STD_I64LE, H5T_NATIVE_INT64, shape, &v, sizeof v);
    if (readable) out.value = v;
  } else if (kind == 11) {
    const std::int32_t i = static_cast<std::int32_t>(std::clamp<std::int64_t>(v, INT32_MIN, INT32_MAX));
    put_attr(loc, name, H5T_STD_I32BE, H5T_NATIVE_INT32, shape, &i, sizeof i);
    if (int64_only) out.verdict = Verdict::Unknown;
    if (readable) out.value = i;
  } else if (kind == 12) {
    const std::uint8_t u = static_cast<std::uint8_t>(std::clamp<std::int64_t>(v, 0, 255));
    put_attr(loc, name, H5T_STD_U8LE, H5T_NATIVE_UINT8, shape, &u, sizeof u);
    if (int64_only) out.verdict = Verdict::Unknown;
    if (readable) out.value = u;
  } else if (kind == 13) {
    const std::uint64_t u = static_cast<std::uint64_t>(v);  // negative: wraps, as a writer's bug would
    put_attr(loc, name, H5T_STD_U64LE, H5T_NATIVE_UINT64, shape, &u, sizeof u);
    out.verdict = Verdict::Unknown;  // a value above INT64_MAX has no int64 reading
  } else if (kind == 14) {  // float where an integer belongs: wrong type
    const double d = static_cast<double>(v);
    put_attr(loc, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, shape, &d, sizeof d);
    out.verdict = Verdict::Invalid;
  } else {
    put_vlen_string(loc, name, std::to_string(v), H5T_CSET_ASCII, shape);
    out.verdict = Verdict::Invalid;
  }
  return out;
}

// A string attribute whose ordinary values are `names`. `value`: what a
// correct reader gets; `verdict` of the type/shape, and Unknown for strings
// whose reading the format leaves open (embedded NUL, trailing blanks).
struct Str {
  bool present = false;
  Verdict verdict = Verdict::Valid;  // of the type and shape
  bool murky = false;                // embedded NUL or trailing blank: the value's reading is open
  std::optional<std::string> value;
};

Str str_attr(ByteReader& r, hid_t loc, const char* name, const std::vector<std::string>& names,
             std::string& notes) {
  Str out;
  out.present = true;
  std::string v;
  switch (r.pick(16)) {
    case 10: v = ""; break;
    case 11:
      v = names[r.pick(names.size())];
      for (auto& c : v) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      break;
    case 12: v = names[r.pick(names.size())] + " "; break;
    case 13: v = names[r.pick(names.size())] + std::string("\0x", 2); break;
    case 14: v = r.str(40); break;
    case 15: v = std::string(300, 'x'); break;
    default: v = names[r.pick(names.size())]; break;
  }
  const bool murky = v.find('\0') != std::string::npos || (!v.empty() && v.back() == ' ');
  const std::string c_str = v.substr(0, v.find('\0'));  // what a C string of it holds
  const unsigned kind = static_cast<unsigned>(r.pick(16));
  notes += " " + std::string(name) + "='" + c_str + "'(t" + std::to_string(kind) + ")";
  if (kind < 9) {
    put_vlen_string(loc, name, v, H5T_CSET_UTF8, Shape::Scalar);
    out.value = c_str;
  } else if (kind == 9) {
    put_vlen_string(loc, name, v, H5T_CSET_ASCII, Shape::Scalar);
    out.value = c_str;
  } else if (kind <= 11) {
    put_fixed_string(loc, name, v, H5T_STR_NULLTERM, 0);
    out.value = c_str;
  } else if (kind == 12) {
    put_fixed_string(loc, name, v, H5T_STR_NULLPAD, r.pick(4));
    out.value = c_str;
  } else if (kind == 13) {  // space-padded (MATLAB, Fortran): the padding is not part of the value
    put_fixed_string(loc, name, v, H5T_STR_SPACEPAD, r.pick(4));
    std::string s = c_str;
    while (!s.empty() && s.back() == ' ') s.pop_back();
    out.value = s;
  } else if (kind == 14) {  // a number where a string belongs: wrong type
    const double d = 1.0;
    put_attr(loc, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, Shape::Scalar, &d, sizeof d);
    out.verdict = Verdict::Invalid;
    return out;
  } else {  // a [2] array of strings
    put_vlen_string(loc, name, v, H5T_CSET_UTF8, Shape::Two);
    out.verdict = Verdict::Unknown;
    return out;
  }
  out.murky = murky;
  return out;
}

// Verdict of a string that must be one of `names`.
Verdict one_of(const Str& s, const std::vector<std::string>& names) {
  if (s.verdict != Verdict::Valid || !s.value) return s.verdict;
  if (s.murky) return Verdict::Unknown;
  for (const auto& n : names)
    if (*s.value == n) return Verdict::Valid;
  return Verdict::Invalid;
}

// Verdict of an optional number that the format does not bound.
Verdict optional_number(const Num& n) {
  if (!n.present) return Verdict::Valid;
  if (n.verdict == Verdict::Invalid) return Verdict::Invalid;
  if (n.verdict == Verdict::Unknown || !n.value || !std::isfinite(*n.value) || !(*n.value > 0))
    return Verdict::Unknown;
  return Verdict::Valid;
}

// Verdict of a required positive number (R1, sample rate) with a plausible range.
Verdict required_positive(const Num& n, double lo, double hi) {
  if (!n.present || n.verdict == Verdict::Invalid) return Verdict::Invalid;
  if (n.value && std::isfinite(*n.value) && *n.value <= 0) return Verdict::Invalid;
  if (n.verdict == Verdict::Unknown || !n.value || !(*n.value >= lo && *n.value <= hi)) return Verdict::Unknown;
  return Verdict::Valid;
}

// ------------------------------------------------------------ signals
const std::vector<std::string> kExcitations = {"exp_decay", "sine", "chirp", "noise", "arbitrary"};
const std::vector<std::string> kRoles = {"dut", "open", "short", "load"};

std::size_t pick_length(ByteReader& r, bool allow_huge) {
  static constexpr std::size_t kTable[] = {16, 17, 24, 32, 64, 100, 128, 256};
  switch (r.pick(16)) {
    case 8: return 0;
    case 9: return 1;
    case 10: return 15;
    case 11: return 16 + r.u16() % 2000;
    case 12: return 1000;
    case 13: return 4096;
    case 14: {  // the same bytes are read either way: a recipe means one file layout everywhere
      static constexpr std::size_t kHuge[] = {std::size_t{1} << 20, std::size_t{1} << 27,
                                              std::size_t{1} << 31, std::size_t{1} << 40};
      const std::size_t huge = kHuge[r.pick(4)];
      return allow_huge ? huge : 64;
    }
    default: return kTable[r.pick(8)];
  }
}

constexpr std::size_t kHugeFrom = std::size_t{1} << 20;  // declared, never written, not predicted

std::vector<double> base_samples(ByteReader& r, std::size_t n) {
  std::vector<double> v(n >= kHugeFrom ? 0 : n);
  const unsigned mode = static_cast<unsigned>(r.pick(8));
  for (std::size_t i = 0; i < v.size(); ++i) {
    switch (mode) {
      case 1: v[i] = 0.0; break;
      case 2: v[i] = std::sin(0.1 * static_cast<double>(i)); break;
      case 3: v[i] = r.empty() ? 0.0 : r.raw_double(); break;
      case 4: v[i] = static_cast<std::int8_t>(r.u8()) * 0.01; break;
      case 5: v[i] = 1e30; break;
      default: v[i] = i < 4 ? 0.0 : std::exp(-3000.0 * static_cast<double>(i - 4) / 1e7); break;
    }
  }
  return v;
}

struct Signal {
  Verdict attrs = Verdict::Valid, samples = Verdict::Valid;
  std::optional<std::vector<double>> values;  // as a correct reader returns them
};

Signal signal(ByteReader& r, hid_t shot, const char* name, std::size_t n, std::vector<double> v,
              std::string& notes) {
  Signal out;
  if (r.pick(24) == 23) {  // missing
    out.attrs = Verdict::Invalid;
    notes += std::string(" ") + name + "=missing";
    return out;
  }
  // Damage one sample now and then.
  if (!v.empty() && r.pick(6) == 5) {
    static constexpr double kBad[] = {kNaN, kInf, -kInf, 1e300, -1e300, 4.9e-324, -0.0, 3.5e38};
    v[r.pick(v.size())] = kBad[r.pick(8)];
  }
  const unsigned dt = static_cast<unsigned>(r.pick(32));
  const unsigned sh = static_cast<unsigned>(r.pick(32));
  const unsigned layout = static_cast<unsigned>(r.pick(8));
  char note[96];
  std::snprintf(note, sizeof note, " %s=N%zu(d%u,s%u,l%u)", name, n, dt, sh, layout);
  notes += note;

  // File type; float types are the valid ones.
  hid_t ftype = H5T_IEEE_F64LE;
  std::optional<Id> custom;
  bool f32 = false;
  if (dt < 14) ftype = H5T_IEEE_F64LE;
  else if (dt < 16) ftype = H5T_IEEE_F64BE;
  else if (dt < 24) ftype = H5T_IEEE_F32LE, f32 = true;
  else if (dt < 26) ftype = H5T_IEEE_F32BE, f32 = true;
  else {
    out.attrs = Verdict::Invalid;  // not float32/float64
    if (dt == 26) {  // IEEE half precision
      custom.emplace(H5Tcopy(H5T_IEEE_F32LE), H5Tclose);
      ok(H5Tset_fields(*custom, 15, 10, 5, 0, 10));
      ok(H5Tset_precision(*custom, 16));
      ok(H5Tset_size(*custom, 2));
      ok(H5Tset_ebias(*custom, 15));
      ftype = *custom;
    } else if (dt == 27) ftype = H5T_NATIVE_LDOUBLE;
    else if (dt == 28) ftype = H5T_STD_I16LE;
    else if (dt == 29) ftype = H5T_STD_I32BE;
    else if (dt == 30) {
      custom.emplace(H5Tcopy(H5T_C_S1), H5Tclose);
      ok(H5Tset_size(*custom, 8));
      ftype = *custom;
    } else {
      custom.emplace(H5Tcreate(H5T_COMPOUND, sizeof(double)), H5Tclose);
      ok(H5Tinsert(*custom, "v", 0, H5T_IEEE_F64LE));
      ftype = *custom;
    }
  }
  const bool numeric_ftype = dt < 30;

  // Shape: rank 1 is the valid one.
  std::vector<hsize_t> dims = {n};
  bool null_space = false;
  if (sh == 28) dims = {};
  else if (sh == 29) dims = {n, 1};
  else if (sh == 30) dims = {2, n / 2};
  else if (sh == 31) null_space = true;
  if (dims.size() != 1 || null_space) out.attrs = Verdict::Invalid;
  Id space(null_space ? H5Screate(H5S_NULL)
                      : dims.empty() ? H5Screate(H5S_SCALAR)
                                     : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
           H5Sclose);
  hsize_t elems = 1;
  for (auto d : dims) elems *= d;
  if (null_space) elems = 0;

  // Layout and fill value.
  Id dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  const bool huge = n >= kHugeFrom;
  bool write = !huge && numeric_ftype && elems > 0 && !(layout == 7);
  double fill = 0.0;
  if (layout == 7 || huge) {
    static constexpr double kFill[] = {0.0, kNaN, 1.5, kInf};
    fill = huge ? 0.0 : kFill[r.pick(4)];
    if (numeric_ftype) ok(H5Pset_fill_value(dcpl, H5T_NATIVE_DOUBLE, &fill));
  }
  const bool simple = !null_space && !dims.empty() && elems > 0;
  if (simple && (huge || layout == 3 || layout == 5 || layout == 6)) {
    std::vector<hsize_t> chunk(dims.size());
    for (std::size_t k = 0; k < dims.size(); ++k)
      chunk[k] = std::max<hsize_t>(1, std::min<hsize_t>(dims[k], huge ? 4096 : 1 + r.pick(64)));
    ok(H5Pset_chunk(dcpl, static_cast<int>(chunk.size()), chunk.data()));
    if (layout == 5) ok(H5Pset_deflate(dcpl, 1 + r.pick(9)));
    if (layout == 6) {
      ok(H5Pset_shuffle(dcpl));
      ok(H5Pset_fletcher32(dcpl));
    }
  } else if (simple && layout == 4 && elems * 8 <= 16000) {
    ok(H5Pset_layout(dcpl, H5D_COMPACT));
  }
  Id ds(H5Dcreate2(shot, name, ftype, space, H5P_DEFAULT, dcpl, H5P_DEFAULT), H5Dclose);

  // Contents, and what a reader must return.
  std::vector<double> expect;
  if (write) {
    if (f32) {
      std::vector<float> buf(elems);
      for (std::size_t i = 0; i < elems; ++i) buf[i] = to_float(i < v.size() ? v[i] : 0.0);
      ok(H5Dwrite(ds, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()));
      expect.assign(buf.begin(), buf.end());
    } else if (dt < 16) {
      std::vector<double> buf(elems);
      for (std::size_t i = 0; i < elems; ++i) buf[i] = i < v.size() ? v[i] : 0.0;
      ok(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()));
      expect = std::move(buf);
    } else {  // invalid numeric dtypes: written as small integers (no conversion overflow)
      std::vector<double> buf(elems);
      for (std::size_t i = 0; i < elems; ++i) buf[i] = static_cast<double>(i % 100);
      ok(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()));
    }
  } else if (!huge && dt < 26) {  // never written: the fill value everywhere
    expect.assign(elems, f32 ? static_cast<double>(to_float(fill)) : fill);
  }
  // Never written (layout 7: only the fill value): no acquired samples. The
  // format says signals are stored as acquired; the reader refuses a signal
  // whose dataset stores fewer bytes than its samples need (README, Capture files).
  if (!write && !huge && numeric_ftype && elems > 0) out.attrs = worst(out.attrs, Verdict::Invalid);
  if (out.attrs == Verdict::Valid && !huge) {
    for (double x : expect)
      if (!std::isfinite(x)) out.samples = Verdict::Invalid;
    out.values = std::move(expect);
  }
  if (huge) out.attrs = worst(out.attrs, Verdict::Unknown);  // plausibility is the reader's call
  return out;
}

// ------------------------------------------------------------ one shot
void write_shot(ByteReader& r, hid_t shot, ExpectedShot& e, bool allow_huge, std::string& notes) {
  const Num rate = num_attr(r, shot, "sample_rate_hz", 1e7, notes);
  e.attrs = worst(e.attrs, required_positive(rate, 1.0, 1e12));
  if (rate.value) e.rate = rate.value;

  if (r.pick(16) != 15) {
    const Str exc = str_attr(r, shot, "excitation", kExcitations, notes);
    e.attrs = worst(e.attrs, one_of(exc, kExcitations));
    e.excitation = exc.value;
  } else {
    e.attrs = Verdict::Invalid;  // required
    notes += " excitation=missing";
  }
  for (auto [name, typical] : {std::pair{"amplitude_v", 1.0}, std::pair{"decay_per_s", 3000.0},
                               std::pair{"frequency_hz", 5e4}, std::pair{"f_start_hz", 1e3},
                               std::pair{"f_stop_hz", 1.2e5}})
    if (r.flag()) e.attrs = worst(e.attrs, optional_number(num_attr(r, shot, name, typical, notes)));

  // Length first: pretrigger_samples is judged against it.
  const std::size_t n = pick_length(r, allow_huge);
  if (n < 16) e.attrs = Verdict::Invalid;  // N >= 16
  if (r.pick(4) != 0) {
    static const std::int64_t kOdd[] = {-1, INT64_MIN, INT64_MAX, 0};
    std::int64_t pre;
    switch (r.pick(16)) {
      case 8: pre = static_cast<std::int64_t>(n) - 1; break;
      case 9: pre = static_cast<std::int64_t>(n); break;
      case 10: case 11: pre = kOdd[r.pick(4)]; break;
      case 12: pre = r.u32(); break;
      default: pre = static_cast<std::int64_t>(r.pick(std::min<std::size_t>(std::max<std::size_t>(n, 1), 16)));
    }
    const Int p = int_attr(r, shot, "pretrigger_samples", pre, true, notes);
    Verdict v = p.verdict;
    if (v == Verdict::Valid && !(p.value && *p.value >= 0 && static_cast<std::uint64_t>(*p.value) < n))
      v = Verdict::Unknown;  // outside [0, N): meaningless, but the format does not say it
    e.attrs = worst(e.attrs, v);
    if (v == Verdict::Valid) e.pretrigger = p.value;
  } else {
    e.pretrigger = 0;  // default
  }

  std::string role = "dut";
  if (r.pick(3) == 2) {
    const Str s = str_attr(r, shot, "role", kRoles, notes);
    const Verdict v = one_of(s, kRoles);
    e.attrs = worst(e.attrs, v);
    role = v == Verdict::Valid ? *s.value : "?";
  }
  if (role != "?") e.role = role;
  if (role == "load" ? r.pick(8) != 7 : r.pick(3) == 2) {
    const Num load = num_attr(r, shot, "load_ohm", 1000.0, notes);
    if (role == "load" && (!load.present || load.verdict == Verdict::Invalid))
      e.load_rules = Verdict::Invalid;
    else
      e.load_rules = optional_number(load);
  } else if (role == "load") {
    e.load_rules = Verdict::Invalid;  // a load standard without its resistance
  }
  if (r.pick(4) == 3) {
    const Num c = num_attr(r, shot, "load_parallel_f", 1e-10, notes);  // default 0: zero is fine
    e.load_rules = worst(e.load_rules, c.present && c.value && *c.value == 0 && c.verdict == Verdict::Valid
                                           ? Verdict::Valid
                                           : optional_number(c));
  }
  // Extensions newer readers check against the samples: no expectation.
  for (const char* ext : {"daq_range_v", "v1_range_v", "v2_range_v"})
    if (r.pick(6) == 5 && num_attr(r, shot, ext, 2.0, notes).present) e.attrs = worst(e.attrs, Verdict::Unknown);
  if (r.pick(8) == 7) {
    int_attr(r, shot, "adc_bits", static_cast<std::int64_t>(r.pick(40)), false, notes);
    e.attrs = worst(e.attrs, Verdict::Unknown);
  }
  if (r.pick(8) == 7) put_vlen_string(shot, "comment", "ignored by readers", H5T_CSET_UTF8, Shape::Scalar);

  // The signals: same length unless the recipe says otherwise.
  std::size_t n2 = n;
  if (r.pick(16) == 15) {
    n2 = n >= kHugeFrom ? n / 2 : n + 1 - r.pick(3);  // n-1, n, n+1
    if (n2 != n) e.attrs = Verdict::Invalid;  // length mismatch
  }
  std::vector<double> b1 = base_samples(r, n);
  std::vector<double> b2 = b1;
  if (r.flag()) b2 = base_samples(r, n2);
  for (std::size_t i = 0; i < b2.size(); ++i) b2[i] *= 0.25 * std::cos(0.1 * static_cast<double>(i));
  b2.resize(n2 >= kHugeFrom ? 0 : n2, 0.0);
  const Signal s1 = signal(r, shot, "v1", n, std::move(b1), notes);
  const Signal s2 = signal(r, shot, "v2", n2, std::move(b2), notes);
  e.attrs = worst(e.attrs, worst(s1.attrs, s2.attrs));
  e.samples = worst(s1.samples, s2.samples);
  if (n2 == n) e.n = n;
  e.v1 = s1.values;
  e.v2 = s2.values;
}

// ------------------------------------------------------------ the file
void write_setup(ByteReader& r, hid_t f, ExpectedCapture& e) {
  const unsigned kind = static_cast<unsigned>(r.pick(16));
  if (kind == 13) {
    e.file = Verdict::Invalid;  // missing required group
    e.notes += " setup=missing";
    return;
  }
  if (kind == 14) {
    hsize_t one = 1;
    Id sp(H5Screate_simple(1, &one, nullptr), H5Sclose);
    Id d(H5Dcreate2(f, "setup", H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
    e.file = Verdict::Invalid;  // not a group
    e.notes += " setup=dataset";
    return;
  }
  if (kind == 15) {
    ok(H5Lcreate_soft("/nowhere", f, "setup", H5P_DEFAULT, H5P_DEFAULT));
    e.file = Verdict::Invalid;  // dangling: no group there
    e.notes += " setup=dangling";
    return;
  }
  Id g(H5Gcreate2(f, "setup", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  const Num r1 = num_attr(r, g, "divider_r1_ohm", 3140.0, e.notes);
  e.file = worst(e.file, required_positive(r1, 1e-3, 1e9));
  if (r1.value) e.r1 = r1.value;
  for (const char* s : {"transducer_id", "material", "notes"})
    if (r.flag()) {
      const Str v = str_attr(r, g, s, {"T-001", "apc850", "", "a note"}, e.notes);
      e.file = worst(e.file, v.verdict);  // any text is fine
    }
  for (auto [name, typical] : {std::pair{"inner_diameter_m", 0.016}, std::pair{"outer_diameter_m", 0.019},
                               std::pair{"length_m", 0.02}, std::pair{"density_kg_m3", 7600.0}})
    if (r.flag()) e.file = worst(e.file, optional_number(num_attr(r, g, name, typical, e.notes)));
  if (r.pick(8) == 7) put_vlen_string(g, "operator", "ignored", H5T_CSET_UTF8, Shape::Scalar);
}

void write_shots(ByteReader& r, hid_t f, ExpectedCapture& e, bool allow_huge) {
  const unsigned kind = static_cast<unsigned>(r.pick(16));
  if (kind >= 13) {
    e.file = Verdict::Invalid;
    e.members_known = false;
    if (kind == 14) {
      hsize_t one = 1;
      Id sp(H5Screate_simple(1, &one, nullptr), H5Sclose);
      Id d(H5Dcreate2(f, "shots", H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
    } else if (kind == 15) {
      ok(H5Lcreate_soft("/nowhere", f, "shots", H5P_DEFAULT, H5P_DEFAULT));
    }
    e.notes += " shots=" + std::to_string(kind);
    return;
  }
  Id gcpl(H5Pcreate(H5P_GROUP_CREATE), H5Pclose);
  if (r.flag()) ok(H5Pset_link_creation_order(gcpl, H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED));
  Id shots(H5Gcreate2(f, "shots", H5P_DEFAULT, gcpl, H5P_DEFAULT), H5Gclose);

  // Members that are not shots: ignored by readers.
  static const char* const kOther[] = {"00001", "0000001", "00000a", "truth", "x", "000001 ", "-00001"};
  for (std::size_t k = 0, n = r.pick(4); k < n; ++k) {
    const char* name = kOther[r.pick(7)];
    if (H5Lexists(shots, name, H5P_DEFAULT) > 0) continue;
    Id g(H5Gcreate2(shots, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  }

  const std::size_t count = (r.pick(6) + 1) % 6;  // 0 -> one shot, 5 -> none
  if (count == 0) e.file = worst(e.file, Verdict::Unknown);  // no shots: refused, not a format rule
  std::vector<std::string> names;
  std::size_t idx = r.pick(8) == 7 ? r.pick(1000) : 0;
  for (std::size_t k = 0; k < count; ++k) {
    char name[16];
    std::snprintf(name, sizeof name, "%06zu", idx);
    names.push_back(name);
    idx += 1 + (r.pick(8) == 7 ? r.pick(1000) : 0);
  }
  if (r.pick(4) == 3) std::reverse(names.begin(), names.end());  // creation order != name order
  for (std::size_t k = 0; k < names.size(); ++k) {
    ExpectedShot s;
    s.name = names[k];
    e.notes += " [" + s.name + "]";
    const unsigned member = static_cast<unsigned>(r.pick(16));
    if (member == 13) {  // a dataset under a shot name
      hsize_t one = 1;
      Id sp(H5Screate_simple(1, &one, nullptr), H5Sclose);
      Id d(H5Dcreate2(shots, s.name.c_str(), H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
           H5Dclose);
      s.attrs = Verdict::Invalid;
      e.notes += "dataset";
    } else if (member == 14 && k > 0) {  // an alias of an earlier shot
      ok(H5Lcreate_soft(("/shots/" + names[k - 1]).c_str(), shots, s.name.c_str(), H5P_DEFAULT, H5P_DEFAULT));
      s.attrs = Verdict::Unknown;
      e.notes += "alias";
    } else if (member == 15) {
      ok(H5Lcreate_soft("/shots/nowhere", shots, s.name.c_str(), H5P_DEFAULT, H5P_DEFAULT));
      s.attrs = Verdict::Unknown;
      e.notes += "dangling";
    } else {
      Id g(H5Gcreate2(shots, s.name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
      write_shot(r, g, s, allow_huge, e.notes);
    }
    e.shots.push_back(std::move(s));
  }
  std::sort(e.shots.begin(), e.shots.end(),
            [](const ExpectedShot& a, const ExpectedShot& b) { return a.name < b.name; });
}

void write_root(ByteReader& r, hid_t f, ExpectedCapture& e) {
  if (r.pick(12) != 11) {
    const Str fmt = str_attr(r, f, "format", {"piezo-capture"}, e.notes);
    e.file = worst(e.file, one_of(fmt, {"piezo-capture"}));
  } else {
    e.file = Verdict::Invalid;
    e.notes += " format=missing";
  }
  if (r.pick(12) != 11) {
    static const std::int64_t kOther[] = {2, 0, -1, INT64_MAX};
    const std::int64_t v = r.pick(16) < 12 ? 1 : kOther[r.pick(4)];
    const Int ver = int_attr(r, f, "format_version", v, false, e.notes);
    Verdict vv = ver.verdict;
    if (vv != Verdict::Invalid && ver.value && *ver.value != 1) vv = Verdict::Invalid;
    e.file = worst(e.file, vv);
  } else {
    e.file = Verdict::Invalid;
    e.notes += " format_version=missing";
  }
  for (const char* s : {"created_utc", "software"})
    if (r.flag()) {
      const Str v = str_attr(r, f, s, {"2024-05-01T12:00:00Z", "piezobench 0.1.0", "h5py"}, e.notes);
      e.file = worst(e.file, v.verdict);  // any text is fine
    }
}

}  // namespace

std::optional<ExpectedCapture> write_capture_recipe(ByteReader& r, const fs::path& path, bool allow_huge) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  ExpectedCapture e;
  try {
    Id fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    ok(H5Pset_fapl_core(fapl, 1 << 16, /*backing_store=*/1));
    if (r.flag()) ok(H5Pset_libver_bounds(fapl, H5F_LIBVER_LATEST, H5F_LIBVER_LATEST));
    Id f(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl), H5Fclose);
    // Order of creation varies too (attributes before or after groups).
    const bool root_first = r.flag();
    if (root_first) write_root(r, f, e);
    write_setup(r, f, e);
    write_shots(r, f, e, allow_huge);
    if (!root_first) write_root(r, f, e);
    if (r.pick(4) == 3) {  // ground truth of a simulated capture: ignored
      Id g(H5Gcreate2(f, "truth", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
      const double v = 6.66e10;
      put_attr(g, "c11_pa", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, Shape::Scalar, &v, sizeof v);
    }
  } catch (const Refused&) {
    H5Eclear2(H5E_DEFAULT);
    return std::nullopt;
  }
  return e;
}

}  // namespace piezo::fuzz
