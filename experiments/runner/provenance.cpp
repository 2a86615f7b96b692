// Provenance of experiment results (provenance.json): config SHA-256, source, build, machine.
#include "experiments/runner/experiment.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "experiments/runner/runner_internal.hpp"
#include "framework/io/io.hpp"

extern char** environ;

namespace ndc {
namespace fs = std::filesystem;
using runner_detail::jsonNumber;
using runner_detail::Tally;
using runner_detail::trimmed;

// --- SHA-256 (FIPS 180-4) ----------------------------------------------------------------------

std::string sha256Hex(std::string_view text) {
  static constexpr std::uint32_t kK[64] = {
      0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4,
      0xab1c5ed5, 0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe,
      0x9bdc06a7, 0xc19bf174, 0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f,
      0x4a7484aa, 0x5cb0a9dc, 0x76f988da, 0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7,
      0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967, 0x27b70a85, 0x2e1b2138, 0x4d2c6dfc,
      0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85, 0xa2bfe8a1, 0xa81a664b,
      0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070, 0x19a4c116,
      0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
      0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7,
      0xc67178f2};
  std::uint32_t h[8] = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                        0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
  // Padding: 0x80, zeros, and the bit length as a big-endian 64-bit number.
  std::string data(text);
  const std::uint64_t bits = static_cast<std::uint64_t>(text.size()) * 8;
  data += static_cast<char>(0x80);
  while (data.size() % 64 != 56) data += '\0';
  for (int i = 7; i >= 0; --i) data += static_cast<char>((bits >> (8 * i)) & 0xff);
  const auto rotr = [](std::uint32_t x, int n) { return (x >> n) | (x << (32 - n)); };
  for (std::size_t block = 0; block < data.size(); block += 64) {
    std::uint32_t w[64];
    for (int t = 0; t < 16; ++t)
      w[t] = (std::uint32_t(static_cast<unsigned char>(data[block + 4 * t])) << 24) |
             (std::uint32_t(static_cast<unsigned char>(data[block + 4 * t + 1])) << 16) |
             (std::uint32_t(static_cast<unsigned char>(data[block + 4 * t + 2])) << 8) |
             std::uint32_t(static_cast<unsigned char>(data[block + 4 * t + 3]));
    for (int t = 16; t < 64; ++t) {
      const std::uint32_t s0 = rotr(w[t - 15], 7) ^ rotr(w[t - 15], 18) ^ (w[t - 15] >> 3);
      const std::uint32_t s1 = rotr(w[t - 2], 17) ^ rotr(w[t - 2], 19) ^ (w[t - 2] >> 10);
      w[t] = w[t - 16] + s0 + w[t - 7] + s1;
    }
    std::uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], k = h[7];
    for (int t = 0; t < 64; ++t) {
      const std::uint32_t t1 =
          k + (rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25)) + ((e & f) ^ (~e & g)) + kK[t] + w[t];
      const std::uint32_t t2 =
          (rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
      k = g;
      g = f;
      f = e;
      e = d + t1;
      d = c;
      c = b;
      b = a;
      a = t1 + t2;
    }
    h[0] += a, h[1] += b, h[2] += c, h[3] += d, h[4] += e, h[5] += f, h[6] += g, h[7] += k;
  }
  char hex[65];
  for (int i = 0; i < 8; ++i) std::snprintf(hex + 8 * i, 9, "%08x", h[i]);
  return std::string(hex, 64);
}

// --- Provenance ------------------------------------------------------------------------------

// Set by CMake for this file (CMakeLists.txt); the fallbacks keep other builds compiling.
#ifndef NDC_COMPILER
#define NDC_COMPILER "unknown"
#endif
#ifndef NDC_CXX_FLAGS
#define NDC_CXX_FLAGS "unknown"
#endif
#ifndef NDC_BUILD_TYPE
#define NDC_BUILD_TYPE "unknown"
#endif
#ifndef NDC_SOURCE_DIR
#define NDC_SOURCE_DIR ""
#endif

namespace {

template <class T>
std::string jsonArray(const std::vector<T>& values) {
  std::string text = "[";
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i) text += ", ";
    if constexpr (std::is_same_v<T, std::string>)
      text += jsonQuoted(values[i]);
    else
      text += std::to_string(values[i]);
  }
  return text + "]";
}

/// Standard output of a program run without a shell; nullopt when it cannot start or fails.
std::optional<std::string> capture(const std::vector<std::string>& argv) {
  int fds[2];
  if (::pipe(fds) != 0) return std::nullopt;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_addclose(&actions, fds[0]);
  posix_spawn_file_actions_addclose(&actions, fds[1]);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = ::posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[1]);
  if (rc != 0) {
    ::close(fds[0]);
    return std::nullopt;
  }
  std::string out;
  char buffer[4096];
  ssize_t got = 0;
  while ((got = ::read(fds[0], buffer, sizeof buffer)) > 0 || (got < 0 && errno == EINTR))
    if (got > 0 && out.size() < (1u << 20)) out.append(buffer, got);
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) return std::nullopt;
  return out;
}

/// The value after "key:" on the first line of a /proc file that starts with `key`.
std::string procField(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key, 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return trimmed(line.substr(colon + 1));
    }
  return "";
}

/// The `executor` field: `{"name": "local"}`, or for Slurm also the job id (null when nothing
/// was submitted), the number of tasks, the partition and the further sbatch options.
std::string executorJson(const ExperimentOptions& o, const Tally& tally) {
  if (o.executor != Executor::slurm) return "{\"name\": \"local\"}";
  return "{\"name\": \"slurm\", \"job_id\": " +
         (tally.slurmJobId.empty() ? std::string("null") : jsonQuoted(tally.slurmJobId)) +
         ", \"tasks\": " + std::to_string(tally.slurmTasks) +
         ", \"partition\": " + jsonQuoted(o.slurmPartition) +
         ", \"sbatch_args\": " + jsonArray(o.slurmArgs) + "}";
}

}  // namespace

namespace runner_detail {

std::string trimmed(std::string s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
  std::size_t start = 0;
  while (start < s.size() && std::isspace(static_cast<unsigned char>(s[start]))) ++start;
  return s.substr(start);
}

std::string utcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  ::gmtime_r(&now, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buffer;
}

std::string provenanceJson(const ExperimentConfig& c, const ExperimentOptions& o,
                           const Tally& tally, const std::string& started) {
  // git: the revision of the source tree the tool was built from ("unknown" without git).
  const std::string source = std::string(NDC_SOURCE_DIR).empty() ? c.root.string() : NDC_SOURCE_DIR;
  const auto revision = capture({"git", "-C", source, "rev-parse", "HEAD"});
  const auto status =
      revision ? capture({"git", "-C", source, "status", "--porcelain", "--untracked-files=no"})
               : std::nullopt;
  char host[256] = "unknown";
  if (::gethostname(host, sizeof host) != 0) std::strcpy(host, "unknown");
  host[sizeof host - 1] = '\0';
  const std::string memory = procField("/proc/meminfo", "MemTotal");  // "24576000 kB"
  const long long memoryBytes = memory.empty() ? -1 : std::atoll(memory.c_str()) * 1024LL;
  std::error_code ec;
  const fs::path executable = fs::read_symlink("/proc/self/exe", ec);

  std::vector<std::string> problems, files;
  for (const ExperimentProblem& p : c.problems) {
    problems.push_back(p.name);
    files.push_back(p.file);
  }
  std::ostringstream j;
  j << "{\n  \"schema\": \"ndcontour.provenance/1\",\n"
    << "  \"experiment\": " << jsonQuoted(c.id) << ",\n"
    << "  \"artefact\": " << jsonQuoted(c.artefact) << ",\n"
    << "  \"description\": " << jsonQuoted(c.description) << ",\n"
    << "  \"config\": {\"file\": " << jsonQuoted(c.file.string())
    << ", \"sha256\": " << jsonQuoted(sha256Hex(c.text))
    << ", \"quick\": " << (c.quick ? "true" : "false") << "},\n"
    << "  \"command\": " << jsonQuoted(o.commandLine) << ",\n"
    << "  \"git\": {\"revision\": " << jsonQuoted(revision ? trimmed(*revision) : "unknown")
    << ", \"dirty\": " << (status ? (trimmed(*status).empty() ? "false" : "true") : "null")
    << ", \"source_dir\": " << jsonQuoted(source) << "},\n"
    << "  \"build\": {\"version\": " << jsonQuoted(NDC_VERSION)
    << ", \"compiler\": " << jsonQuoted(NDC_COMPILER)
    << ", \"flags\": " << jsonQuoted(trimmed(NDC_CXX_FLAGS))
    << ", \"build_type\": " << jsonQuoted(NDC_BUILD_TYPE)
    << ", \"executable\": " << jsonQuoted(executable.string()) << "},\n"
    << "  \"grid\": {\"problems\": " << jsonArray(problems) << ",\n"
    << "           \"problem_files\": " << jsonArray(files) << ",\n"
    << "           \"bounding\": " << jsonArray(c.bounding)
    << ", \"subdivision\": " << jsonArray(c.subdivision)
    << ", \"projection\": " << jsonArray(c.projection)
    << ", \"classification\": " << jsonArray(c.classification)
    << ", \"connection\": " << jsonArray(c.connection) << ",\n"
    << "           \"scalar\": " << jsonArray(c.scalar)
    << ", \"precision_bits\": " << jsonArray(c.precision) << ", \"depths\": " << jsonArray(c.depths)
    << ", \"seeds\": " << (c.seeds.empty() ? std::string("null") : jsonArray(c.seeds))
    << ", \"timeout_s\": " << jsonNumber(c.timeoutS)
    << ", \"cells\": " << (c.cells ? "true" : "false") << "},\n"
    << "  \"runs\": {\"total\": " << tally.total << ", \"ran\": " << tally.ran
    << ", \"skipped\": " << tally.skipped << ", \"failed\": " << tally.failed
    << ", \"failed_runs\": " << jsonArray(tally.failedRuns) << ", \"jobs\": " << o.jobs << "},\n"
    << "  \"executor\": " << executorJson(o, tally) << ",\n"
    << "  \"date\": " << jsonQuoted(started) << ",\n"
    << "  \"finished\": " << jsonQuoted(utcNow()) << ",\n"
    << "  \"machine\": {\"hostname\": " << jsonQuoted(host)
    << ", \"nproc\": " << std::max(1u, std::thread::hardware_concurrency())
    << ", \"cpu_model\": " << jsonQuoted(procField("/proc/cpuinfo", "model name"))
    << ", \"memory_bytes\": " << memoryBytes << "}\n}\n";
  return j.str();
}

}  // namespace runner_detail

}  // namespace ndc
