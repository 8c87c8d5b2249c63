#pragma once
// Test support: runs the built `piezobench` binary and captures its output.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace piezo::test {

struct CliResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// Runs `PIEZO_CLI args` through /bin/sh; args must be shell-quoted by the caller.
inline CliResult run_cli(const std::string& args, const std::string& stdin_text = {}) {
  static int counter = 0;
  const std::string errfile = std::filesystem::temp_directory_path().string() + "/piezobench-cli-err-" + std::to_string(::getpid()) + "-" +
                              std::to_string(counter++);
  std::string cmd = std::string(PIEZO_CLI) + " " + args + " 2>" + errfile;
  if (stdin_text.empty()) cmd += " </dev/null";
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) throw std::runtime_error("popen failed");
  CliResult r;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  int status = ::pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  if (FILE* e = std::fopen(errfile.c_str(), "r")) {
    while ((n = std::fread(buf.data(), 1, buf.size(), e)) > 0) r.err.append(buf.data(), n);
    std::fclose(e);
  }
  std::remove(errfile.c_str());
  return r;
}

}  // namespace piezo::test
