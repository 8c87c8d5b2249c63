#pragma once
// SHA-256 of a file or a byte string, as lowercase hex, through OpenSSL's
// libcrypto (EVP interface; Debian's libssl-dev). Replay records every input
// by path and digest, so a changed file is never mistaken for a finished one.
#include <filesystem>
#include <string>
#include <string_view>

namespace piezo::jobs::replay {

// Throws std::runtime_error naming the file when it cannot be read.
std::string sha256_file(const std::filesystem::path& file);
std::string sha256_bytes(std::string_view bytes);

}  // namespace piezo::jobs::replay
