// Child processes of `ndcontour solve`: starting, stopping, interrupts, reading back outcomes.
#include "experiments/runner/runner_internal.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "framework/util/errors.hpp"
#include "framework/util/json.hpp"

extern char** environ;

namespace ndc {
namespace fs = std::filesystem;
using runner_detail::Clock;
using runner_detail::gInterrupted;
using runner_detail::jsonNumber;
using runner_detail::Outcome;
using runner_detail::readFile;
using runner_detail::trimmed;

namespace {

void onInterrupt(int signal) { gInterrupted = signal; }

/// The last non-empty line of a file (of its last 64 KiB), at most 300 characters.
std::string lastLine(const fs::path& file) {
  std::ifstream in(file, std::ios::binary | std::ios::ate);
  if (!in) return "";
  const std::streamoff size = in.tellg();
  const std::streamoff from = std::max<std::streamoff>(0, size - 65536);
  in.seekg(from);
  std::string text(static_cast<std::size_t>(size - from), '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  std::string line;
  std::istringstream lines(text);
  for (std::string l; std::getline(lines, l);)
    if (!trimmed(l).empty()) line = trimmed(l);
  if (line.size() > 300) line = line.substr(0, 297) + "...";
  return oneLine(line);
}

}  // namespace

namespace runner_detail {

volatile std::sig_atomic_t gInterrupted = 0;

std::vector<int> stopChildren(const std::vector<pid_t>& pids) {
  std::vector<int> statuses(pids.size(), 0);
  std::vector<bool> done(pids.size(), false);
  for (pid_t pid : pids) ::kill(pid, SIGTERM);
  const auto deadline = Clock::now() + std::chrono::seconds(1);
  for (std::size_t left = pids.size(); left > 0;) {
    for (std::size_t i = 0; i < pids.size(); ++i) {
      if (done[i]) continue;
      const bool late = Clock::now() > deadline;
      if (late) ::kill(pids[i], SIGKILL);
      const pid_t got = ::waitpid(pids[i], &statuses[i], late ? 0 : WNOHANG);
      if (got == pids[i] || (got < 0 && errno != EINTR)) {
        done[i] = true;
        --left;
      }
    }
    if (left > 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return statuses;
}

Outcome readSummary(const fs::path& runDir) {
  Outcome o;
  o.status = "ok";
  o.exitCode = 0;
  try {
    o.values = flattenJsonNumbers(readFile(runDir / "summary.json"));
  } catch (const std::exception& e) {
    o.status = "error";
    o.exitCode.reset();
    o.error = "summary.json: " + std::string(e.what());
  }
  return o;
}

Outcome outcomeOf(const fs::path& runDir, int status, bool timedOut, double timeoutS) {
  const std::string last = lastLine(runDir / "stderr.txt");
  std::error_code ec;
  const bool summary = fs::exists(runDir / "summary.json", ec);
  // A summary written before the kill is a finished run, as it will be on resume.
  if (summary && (timedOut || (WIFEXITED(status) && WEXITSTATUS(status) == 0)))
    return readSummary(runDir);
  Outcome o;
  if (timedOut) {
    o.status = "timeout";
    o.error = "timed out after " + jsonNumber(timeoutS) + " s" + (last.empty() ? "" : ": " + last);
  } else if (WIFEXITED(status)) {
    o.exitCode = WEXITSTATUS(status);
    o.status = *o.exitCode == 0 ? "error" : "failed";
    o.error = *o.exitCode == 0 ? "exited 0 without writing summary.json"
              : last.empty()   ? "exit status " + std::to_string(*o.exitCode)
                               : last;
  } else if (WIFSIGNALED(status)) {
    o.status = "crashed";
    o.exitCode = -WTERMSIG(status);
    o.error = "killed by signal " + std::to_string(WTERMSIG(status)) + " (" +
              ::strsignal(WTERMSIG(status)) + ")" + (last.empty() ? "" : ": " + last);
  } else {
    o.status = "error";
    o.error = "unknown wait status " + std::to_string(status);
  }
  return o;
}

std::vector<std::string> solveArguments(const std::string& problem, const std::string& runDir,
                                        const Settings& s, bool cells) {
  std::vector<std::string> a = {"solve",
                                problem,
                                "--out",
                                runDir,
                                "--depth",
                                std::to_string(s.depth),
                                "--bounding",
                                s.bounding,
                                "--subdivision",
                                s.subdivision,
                                "--classification",
                                s.classification,
                                "--connection",
                                s.connection,
                                "--scalar",
                                s.scalar};
  if (s.scalar != "double") {
    a.push_back("--precision");
    a.push_back(std::to_string(s.precisionBits));
  }
  if (s.jitter) {
    a.push_back("--jitter");
    a.push_back(std::to_string(*s.jitter));
  }
  if (s.threads > 0) {
    a.push_back("--threads");
    a.push_back(std::to_string(s.threads));
  }
  if (s.maxMemoryBytes > 0) {
    a.push_back("--max-memory");
    a.push_back(std::to_string(s.maxMemoryBytes));
  }
  if (cells) a.push_back("--cells");
  a.push_back("--json");
  return a;
}

pid_t spawnRun(const std::string& executable, const std::vector<std::string>& arguments,
               const fs::path& stderrFile, std::string& error, const fs::path& stdoutFile) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  const std::string out = stdoutFile.string();
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const std::string err = stderrFile.string();
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<char*> args = {const_cast<char*>(executable.c_str())};
  for (const std::string& a : arguments) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = -1;
  const int rc = ::posix_spawn(&pid, executable.c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    error = "cannot start " + executable + ": " + std::strerror(rc);
    return -1;
  }
  return pid;
}

std::optional<Ended> pollChild(pid_t pid, Clock::time_point start, double timeoutS) {
  Ended e;
  const pid_t got = ::waitpid(pid, &e.status, WNOHANG);
  e.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (got == 0 && e.seconds > timeoutS) {
    e.status = stopChildren({pid}).front();
    e.timedOut = true;
    return e;
  }
  if (got == 0 || (got < 0 && errno == EINTR)) return std::nullopt;
  if (got < 0) e.lostErrno = errno;
  return e;
}

Outcome outcomeOfEnded(const fs::path& runDir, const Ended& ended, double timeoutS) {
  Outcome o;
  if (ended.lostErrno != 0) {
    o.status = "error";
    o.error = std::string("lost the child process: ") + std::strerror(ended.lostErrno);
  } else {
    o = outcomeOf(runDir, ended.status, ended.timedOut, timeoutS);
  }
  o.seconds = ended.seconds;
  return o;
}

InterruptScope::InterruptScope() {
  gInterrupted = 0;
  struct sigaction action {};
  action.sa_handler = onInterrupt;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, &savedInt_);
  ::sigaction(SIGTERM, &action, &savedTerm_);
}

InterruptScope::~InterruptScope() {
  ::sigaction(SIGINT, &savedInt_, nullptr);
  ::sigaction(SIGTERM, &savedTerm_, nullptr);
}

}  // namespace runner_detail

}  // namespace ndc
