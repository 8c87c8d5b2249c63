// SHA-256 through libcrypto: the FIPS 180-2 example digests, a file read in
// several buffers, and clear errors for what cannot be read.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "jobs/replay/sha256.hpp"

using namespace piezo;
namespace fs = std::filesystem;

TEST(Sha256, KnownDigests) {
  EXPECT_EQ(jobs::replay::sha256_bytes(""),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(jobs::replay::sha256_bytes("abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(jobs::replay::sha256_bytes("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST(Sha256, FileOfOneMillionAsSpansManyReads) {
  const fs::path f = fs::temp_directory_path() / ("piezobench-sha-" + std::to_string(::getpid()));
  {
    std::ofstream o(f, std::ios::binary);
    o << std::string(1000000, 'a');
  }
  EXPECT_EQ(jobs::replay::sha256_file(f),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  fs::remove(f);
}

TEST(Sha256, UnreadableInputNamesTheFile) {
  try {
    jobs::replay::sha256_file("/no/such/capture.h5");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/no/such/capture.h5"), std::string::npos) << e.what();
  }
  EXPECT_THROW(jobs::replay::sha256_file(fs::temp_directory_path()), std::runtime_error);  // a folder
}
