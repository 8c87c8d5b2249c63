// piezo-capture/1 reader and writer: round trip of every field, each
// validation rule of the reader, what readers must ignore, lenient reads.
#include <gtest/gtest.h>

#include <filesystem>

#include "acquisition/capture_file.hpp"
#include "acquisition/utf8.hpp"
#include "tests/support/capture_mutations.hpp"

namespace fs = std::filesystem;
using namespace piezo;

namespace {
fs::path tmp_dir() {
  auto d = fs::temp_directory_path() /
           ("piezobench-test-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::create_directories(d);
  return d;
}
}  // namespace

TEST(CaptureFile, RoundTripsEveryField) {
  auto dir = tmp_dir();
  acq::Capture cap = test::small_valid_capture(100);
  acq::Shot sine = cap.shots[0];
  sine.excitation = acq::Excitation::Sine;
  sine.frequency_hz = 51234.5;
  sine.role = acq::Role::Load;
  sine.load_ohm = 1000.0;
  sine.load_parallel_f = 22e-12;
  sine.daq_range_v = 2.0;
  sine.store_float32 = true;
  cap.shots.push_back(sine);
  acq::Shot chirp = cap.shots[1];
  chirp.excitation = acq::Excitation::Chirp;
  chirp.f_start_hz = 1e3;
  chirp.f_stop_hz = 1.2e5;
  chirp.role = acq::Role::Open;
  cap.shots.push_back(chirp);

  acq::WriterOptions wo;
  wo.software = "test 1.0";
  acq::write_capture(dir / "rt.h5", cap, wo);
  EXPECT_FALSE(fs::exists(acq::partial_path_for(dir / "rt.h5")));
  auto back = acq::read_capture(dir / "rt.h5");

  EXPECT_EQ(back.software, "test 1.0");
  ASSERT_TRUE(back.created_utc.has_value());
  EXPECT_EQ(back.created_utc->size(), 20u);  // YYYY-MM-DDTHH:MM:SSZ
  EXPECT_EQ(back.setup.divider_r1_ohm, 3140.0);
  EXPECT_EQ(back.setup.transducer_id, "T-001");
  EXPECT_EQ(back.setup.material, "apc850");
  EXPECT_EQ(back.setup.notes, "unit test");
  EXPECT_EQ(back.setup.inner_diameter_m, 0.016);
  EXPECT_EQ(back.setup.outer_diameter_m, 0.019);
  EXPECT_EQ(back.setup.length_m, 0.02);
  EXPECT_EQ(back.setup.density_kg_m3, 7600.0);
  ASSERT_EQ(back.shots.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) {
    const auto& a = cap.shots[k];
    const auto& b = back.shots[k];
    EXPECT_EQ(b.name, (std::vector<std::string>{"000000", "000001", "000002", "000003"}[k]));
    EXPECT_EQ(b.sample_rate_hz, a.sample_rate_hz);
    EXPECT_EQ(b.excitation, a.excitation);
    EXPECT_EQ(b.amplitude_v, a.amplitude_v);
    EXPECT_EQ(b.decay_per_s, a.decay_per_s);
    EXPECT_EQ(b.frequency_hz, a.frequency_hz);
    EXPECT_EQ(b.f_start_hz, a.f_start_hz);
    EXPECT_EQ(b.f_stop_hz, a.f_stop_hz);
    EXPECT_EQ(b.pretrigger_samples, a.pretrigger_samples);
    EXPECT_EQ(b.role, a.role);
    EXPECT_EQ(b.load_ohm, a.load_ohm);
    EXPECT_EQ(b.load_parallel_f, a.load_parallel_f);
    EXPECT_EQ(b.daq_range_v, a.daq_range_v);
    ASSERT_EQ(b.v1.size(), a.v1.size());
    for (std::size_t i = 0; i < a.v1.size(); ++i) {
      if (a.store_float32) {  // float32 storage: exact float rounding of the value
        EXPECT_EQ(b.v1[i], static_cast<double>(static_cast<float>(a.v1[i])));
        EXPECT_EQ(b.v2[i], static_cast<double>(static_cast<float>(a.v2[i])));
      } else {
        EXPECT_EQ(b.v1[i], a.v1[i]);
        EXPECT_EQ(b.v2[i], a.v2[i]);
      }
    }
  }
  fs::remove_all(dir);
}

TEST(CaptureFile, GeometryDefaultsApplyWhenAbsent) {
  acq::Setup s;
  s.divider_r1_ohm = 100;
  s.length_m = 0.03;
  auto g = s.geometry();
  EXPECT_EQ(g.inner_diameter_m, 0.016);
  EXPECT_EQ(g.outer_diameter_m, 0.019);
  EXPECT_EQ(g.length_m, 0.03);
  EXPECT_EQ(g.density_kg_m3, 7600.0);
}

class ReaderDefects : public ::testing::TestWithParam<test::DefectCase> {};

TEST_P(ReaderDefects, RefusedWithFilePathAndProblem) {
  const auto& c = GetParam();
  auto dir = tmp_dir();
  auto file = dir / (std::string(c.name) + ".h5");
  test::make_capture_with_defect(file, c.defect);
  try {
    acq::read_capture(file);
    FAIL() << c.name << ": read_capture accepted a defective file";
  } catch (const acq::CaptureError& e) {
    EXPECT_EQ(e.file(), file.string());
    EXPECT_EQ(e.h5path(), c.h5path) << e.what();
    EXPECT_NE(e.problem().find(c.problem), std::string::npos)
        << "problem '" << e.problem() << "' lacks '" << c.problem << "'";
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos);
  }
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(All, ReaderDefects, ::testing::ValuesIn(test::all_defects()),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(CaptureFile, ReaderIgnoresUnknownGroupsAndAttributes) {
  auto dir = tmp_dir();
  test::make_capture_with_defect(dir / "x.h5", test::Defect::None);
  auto before = acq::read_capture(dir / "x.h5");
  test::add_ignorable_extras(dir / "x.h5");
  auto after = acq::read_capture(dir / "x.h5");
  ASSERT_EQ(after.shots.size(), before.shots.size());
  EXPECT_EQ(after.shots[0].v2, before.shots[0].v2);
  fs::remove_all(dir);
}

TEST(CaptureFile, LenientReadSkipsAnInvalidShotAndSaysWhy) {
  auto dir = tmp_dir();
  test::make_capture_with_defect(dir / "x.h5", test::Defect::NaNSample);
  acq::ReadOptions opt;
  opt.skip_invalid_shots = true;
  auto cap = acq::read_capture(dir / "x.h5", opt);
  ASSERT_EQ(cap.shots.size(), 1u);
  EXPECT_EQ(cap.shots[0].name, "000000");
  ASSERT_EQ(cap.rejected_shots.size(), 1u);
  EXPECT_NE(cap.rejected_shots[0].find("/shots/000001/v1"), std::string::npos);
  fs::remove_all(dir);
}

TEST(CaptureFile, AttributesOnlyReadChecksShapes) {
  auto dir = tmp_dir();
  test::make_capture_with_defect(dir / "x.h5", test::Defect::None);
  acq::ReadOptions opt;
  opt.load_samples = false;
  auto cap = acq::read_capture(dir / "x.h5", opt);
  ASSERT_EQ(cap.shots.size(), 2u);
  EXPECT_TRUE(cap.shots[0].v1.empty());
  test::make_capture_with_defect(dir / "y.h5", test::Defect::LengthMismatch);
  EXPECT_THROW(acq::read_capture(dir / "y.h5", opt), acq::CaptureError);
  fs::remove_all(dir);
}

TEST(CaptureWriter, RefusesAnInvalidShotAndKeepsEarlierOnes) {
  auto dir = tmp_dir();
  auto cap = test::small_valid_capture();
  {
    acq::CaptureWriter w(dir / "w.h5", cap.setup);
    w.append(cap.shots[0]);
    auto bad = cap.shots[1];
    bad.v2.pop_back();
    EXPECT_THROW(w.append(bad), acq::CaptureError);
    bad = cap.shots[1];
    bad.sample_rate_hz = 0;
    EXPECT_THROW(w.append(bad), acq::CaptureError);
    EXPECT_EQ(w.shots_written(), 1u);
    // destroyed without close(): the acquired shot is kept under the final name
  }
  auto back = acq::read_capture(dir / "w.h5");
  ASSERT_EQ(back.shots.size(), 1u);
  EXPECT_EQ(back.shots[0].v1, cap.shots[0].v1);
  fs::remove_all(dir);
}

TEST(CaptureWriter, RefusesToOverwriteUnlessAsked) {
  auto dir = tmp_dir();
  auto cap = test::small_valid_capture();
  acq::write_capture(dir / "w.h5", cap);
  EXPECT_THROW(acq::CaptureWriter(dir / "w.h5", cap.setup), acq::CaptureError);
  acq::WriterOptions o;
  o.overwrite = true;
  EXPECT_NO_THROW(acq::write_capture(dir / "w.h5", cap, o));
  fs::remove_all(dir);
}

TEST(CaptureWriter, RefusesInvalidSetup) {
  auto dir = tmp_dir();
  acq::Setup s;
  s.divider_r1_ohm = -1;
  EXPECT_THROW(acq::CaptureWriter(dir / "w.h5", s), acq::CaptureError);
  s.divider_r1_ohm = 10;
  s.length_m = 0;
  EXPECT_THROW(acq::CaptureWriter(dir / "w.h5", s), acq::CaptureError);
  EXPECT_FALSE(fs::exists(dir / "w.h5"));
  fs::remove_all(dir);
}

// Strings written by other tools (Latin-1, damaged bytes, terminal escapes)
// are read, each offending byte replaced by U+FFFD, so that JSON output and
// terminals get valid text (found by the mutation soak: `capture info --json`
// died on a software attribute holding byte 0x87).
TEST(CaptureFile, StringsThatAreNotUtf8AreReadWithReplacementCharacters) {
  auto dir = tmp_dir();
  acq::Capture cap = test::small_valid_capture(100);
  cap.setup.notes = std::string("line one\nline two\t\xC2\xB5V \xCE\xA9 \xF0\x9F\x94\x8A ok");  // valid UTF-8
  cap.setup.transducer_id = std::string("tube \xB5-7 \x1b[31mred");  // Latin-1 µ, an escape
  acq::write_capture(dir / "s.h5", cap);
  const auto back = acq::read_capture(dir / "s.h5");
  EXPECT_EQ(back.setup.notes, cap.setup.notes);  // valid text is kept byte for byte
  EXPECT_EQ(back.setup.transducer_id, std::string("tube \xEF\xBF\xBD-7 \xEF\xBF\xBD[31mred"));
  fs::remove_all(dir);
}

TEST(Utf8, MalformedSequencesAreReplacedBytePerByte) {
  const std::string r = "\xEF\xBF\xBD";
  EXPECT_EQ(acq::utf8_or_replaced("plain"), "plain");
  EXPECT_EQ(acq::utf8_or_replaced("\xC0\x80"), r + r);              // overlong NUL
  EXPECT_EQ(acq::utf8_or_replaced("\xED\xA0\x80"), r + r + r);      // a UTF-16 surrogate
  EXPECT_EQ(acq::utf8_or_replaced("a\xE2\x82"), "a" + r + r);      // cut short
  EXPECT_EQ(acq::utf8_or_replaced("\xF4\x90\x80\x80"), r + r + r + r);  // above U+10FFFF
  EXPECT_EQ(acq::utf8_or_replaced("\xE2\x82\xAC"), "\xE2\x82\xAC");  // the euro sign
  EXPECT_EQ(acq::utf8_or_replaced(std::string("a\0b", 3)), "a" + r + "b");
  EXPECT_EQ(acq::utf8_or_replaced("\x7F"), r);
}
