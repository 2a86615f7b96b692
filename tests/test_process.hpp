// The command-line tool as a process, for tests: a scratch directory per test process, shell
// quoting, and a run that captures the exit status, stdout and stderr.
#pragma once
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/test_support.hpp"

namespace ndc::test {

/// A directory under the system temporary directory named `ndc-test-TAG-PID`, removed when
/// destroyed.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& tag)
      : path_(std::filesystem::temp_directory_path() /
              ("ndc-test-" + tag + "-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// `s` in single quotes for /bin/sh.
inline std::string quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

/// The whole content of a file (empty when it cannot be read).
inline std::string slurp(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// What a run of the tool returned.
struct CliRun {
  int status = -1;  ///< exit status, -1 when killed by a signal
  std::string out, err;
};

/// Runs `ndcontour ARGS` (ARGS already shell-quoted) with stdin from /dev/null, capturing
/// stdout and stderr through files in `scratch`. With `limitSeconds` > 0 the run is killed
/// (SIGKILL, status 137) when it takes longer.
inline CliRun runNdcontour(const std::string& args, const std::filesystem::path& scratch,
                           int limitSeconds = 0) {
  const auto out = scratch / "stdout.txt", err = scratch / "stderr.txt";
  const std::string limit =
      limitSeconds > 0 ? "timeout -s KILL " + std::to_string(limitSeconds) + " " : "";
  const std::string command = limit + quoted(binaryPath()) + " " + args + " >" +
                              quoted(out.string()) + " 2>" + quoted(err.string()) + " </dev/null";
  const int raw = std::system(command.c_str());
  CliRun run;
  run.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  run.out = slurp(out);
  run.err = slurp(err);
  return run;
}

}  // namespace ndc::test
