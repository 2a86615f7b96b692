// Experiments (experiment.hpp, docs/experiments.md): config validation, the run grid, child
// processes of `ndcontour solve`, the combined CSV and the provenance record.
#include "experiments/runner/experiment.hpp"

#include <fcntl.h>
#include <fnmatch.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "experiments/runner/generate.hpp"
#include "framework/applications/load.hpp"
#include "framework/core/budget.hpp"
#include "framework/core/expectation.hpp"
#include "framework/core/io.hpp"
#include "framework/core/toml_reader.hpp"
#include "framework/pipeline/pipeline.hpp"
#include "strategies/bounding/bounding.hpp"
#include "strategies/classification/classification.hpp"
#include "strategies/connection/connection.hpp"
#include "strategies/projection/newton.hpp"
#include "strategies/subdivision/subdivision.hpp"

extern char** environ;

namespace ndc {
namespace fs = std::filesystem;

namespace {

// --- Small helpers -------------------------------------------------------------------------

/// A strategy spec as part of a run id (a folder name, also in LaTeX and gnuplot paths):
/// `paper:extra_layers=1,thin_thick_normal=false` ->
/// `paper+extra_layers-1+thin_thick_normal-false`.
std::string idPart(std::string spec) {
  for (char& c : spec) c = c == ':' || c == ',' ? '+' : c == '=' ? '-' : c;
  return spec;
}

/// Values of `artefact`.
constexpr std::array<std::string_view, 2> kArtefactNames = {"table", "figure"};
/// Largest number of generator seeds, runs and timeout a config may ask for: bad input, not
/// an unbounded allocation.
constexpr std::int64_t kMaxGeneratorSeeds = 1000;
constexpr std::size_t kMaxRuns = 100000;
constexpr double kMaxTimeoutS = 7 * 24 * 3600.0;

template <std::size_t N>
std::string listed(const std::array<std::string_view, N>& names) {
  std::string text;
  for (std::size_t i = 0; i < N; ++i) text += (i ? ", " : "") + std::string(names[i]);
  return text;
}

std::string readFile(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// Shortest decimal text that reads back as the same double ("null" when not finite).
std::string jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buffer[32];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(buffer, sizeof buffer, "%.*g", digits, v);
    if (std::strtod(buffer, nullptr) == v) break;
  }
  return buffer;
}

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

/// A CSV field (RFC 4180): quoted when it holds a comma, quote or line break.
std::string csvField(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

/// A word for a POSIX shell (command.txt).
std::string shellWord(const std::string& s) {
  const bool plain = !s.empty() && s.find_first_not_of(
                                       "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                       "0123456789_-./=:+@%,") == std::string::npos;
  if (plain) return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace

// --- Config ----------------------------------------------------------------------------------

namespace {

/// One entry of `problems`: the problems it stands for and its own depths and jitter seeds.
struct ProblemEntry {
  const toml::node* node = nullptr;
  std::vector<ExperimentProblem> problems;
  std::optional<std::vector<int>> depths;
  std::optional<std::vector<std::uint64_t>> jitter;
};

/// The grid keys of one table (the top level or `[quick]`); absent keys stay empty.
struct GridFields {
  std::optional<std::vector<ProblemEntry>> problems;
  std::optional<std::vector<std::string>> bounding, subdivision, projection, classification,
      connection, scalar;
  std::optional<std::vector<unsigned>> precision;
  std::optional<std::vector<int>> depths;
  std::optional<std::vector<std::uint64_t>> seeds;
  std::optional<double> timeout;
  const toml::node* precisionNode = nullptr;
};

/// Validation of one config; every failure is an InputError at a position of the file.
class ConfigReader {
 public:
  ConfigReader(const fs::path& file, const std::string& text) : file_(file.string()), text_(text) {
    // Problem paths are relative to the repository root: the directory holding
    // `experiments/configs/` when the config lives there, else the config's own directory.
    const fs::path dir = fs::absolute(file).lexically_normal().parent_path();
    root_ = dir;
    if (dir.filename() == "configs" && dir.parent_path().filename() == "experiments")
      root_ = dir.parent_path().parent_path();
  }

  ExperimentConfig run(const toml::table& top, bool quick) {
    static const std::set<std::string> kTopKeys = {
        "id",          "artefact",   "description", "problems",  "bounding",
        "subdivision", "connection", "scalar",      "precision", "classification",
        "projection",  "depths",     "seeds",       "timeout_s", "quick"};
    for (auto&& [key, node] : top)
      if (!kTopKeys.count(std::string(key.str())))
        fail(key.source(), "unknown key '" + std::string(key.str()) +
                               "' (known: id, artefact, description, problems, bounding, "
                               "subdivision, connection, scalar, precision, classification, "
                               "projection, depths, seeds, timeout_s, quick)");

    ExperimentConfig c;
    c.file = file_;
    c.text = text_;
    c.root = root_;

    // id: names every result file, so it must be the file's stem and a safe file name.
    const toml::node& id = require(top, "id");
    c.id = stringOf(id, "id");
    if (!isProblemName(c.id)) fail(id, "id '" + c.id + "' must match [a-z0-9._-]+");
    const std::string stem = fs::path(file_).stem().string();
    if (c.id != stem)
      fail(id, "id '" + c.id + "' must equal the file name without .toml ('" + stem + "')");
    const toml::node& artefact = require(top, "artefact");
    c.artefact = stringOf(artefact, "artefact");
    if (std::find(kArtefactNames.begin(), kArtefactNames.end(), c.artefact) == kArtefactNames.end())
      fail(artefact,
           "unknown artefact '" + c.artefact + "' (accepted: " + listed(kArtefactNames) + ")");
    c.description = stringOf(require(top, "description"), "description");

    require(top, "problems");
    require(top, "depths");
    const GridFields base = readGrid(top, "");
    GridFields over;
    if (const toml::node* q = top.get("quick")) {
      const toml::table* table = q->as_table();
      if (!table) fail(*q, "quick must be a table, not " + tomlTypeName(*q));
      static const std::set<std::string> kQuickKeys = {
          "problems",       "bounding",   "subdivision", "connection", "scalar",   "precision",
          "classification", "projection", "depths",      "seeds",      "timeout_s"};
      for (auto&& [key, node] : *table)
        if (!kQuickKeys.count(std::string(key.str())))
          fail(key.source(), "unknown key 'quick." + std::string(key.str()) +
                                 "' (known: problems, bounding, subdivision, connection, "
                                 "scalar, precision, classification, projection, depths, seeds, "
                                 "timeout_s)");
      over = readGrid(*table, "quick.");
    }
    // Both modes are validated, whichever runs, so that a config never fails only in CI.
    ExperimentConfig full = c, fast = c;
    finish(full, base, GridFields{});
    finish(fast, base, over);
    fast.quick = true;
    return quick ? fast : full;
  }

 private:
  [[noreturn]] void fail(const toml::source_region& where, const std::string& message) const {
    throw InputError::at(file_, static_cast<int>(where.begin.line),
                         static_cast<int>(where.begin.column), message);
  }
  [[noreturn]] void fail(const toml::node& node, const std::string& message) const {
    fail(node.source(), message);
  }

  const toml::node& require(const toml::table& table, const std::string& key) const {
    const toml::node* node = table.get(key);
    if (!node) throw InputError::at(file_, 0, 0, "missing required key '" + key + "'");
    return *node;
  }

  std::string stringOf(const toml::node& node, const std::string& what) const {
    if (const auto* s = node.as_string()) return s->get();
    fail(node, what + " must be a string, not " + tomlTypeName(node));
  }

  std::int64_t integerOf(const toml::node& node, const std::string& what, std::int64_t lo,
                         std::int64_t hi) const {
    const auto* i = node.as_integer();
    if (!i) fail(node, what + " must be an integer, not " + tomlTypeName(node));
    if (i->get() < lo || i->get() > hi)
      fail(node, what + " = " + std::to_string(i->get()) + " is out of range (accepted: " +
                     std::to_string(lo) + ".." + std::to_string(hi) + ")");
    return i->get();
  }

  /// The elements of a list key: an array (non-empty, no repeats), or one value for short.
  std::vector<const toml::node*> elements(const toml::node& node, const std::string& what) const {
    std::vector<const toml::node*> out;
    if (const toml::array* a = node.as_array()) {
      if (a->empty()) fail(node, what + " must not be empty");
      for (const toml::node& e : *a) out.push_back(&e);
    } else {
      out.push_back(&node);
    }
    return out;
  }

  template <class T>
  void checkDistinct(const std::vector<T>& values, const std::vector<const toml::node*>& nodes,
                     const std::string& what) const {
    for (std::size_t i = 0; i < values.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        if (values[i] == values[j]) fail(*nodes[i], what + " lists a value twice");
  }

  template <std::size_t N>
  std::vector<std::string> names(const toml::node& node, const std::string& what,
                                 const std::array<std::string_view, N>& accepted,
                                 const std::string& family) const {
    const auto nodes = elements(node, what);
    std::vector<std::string> out;
    for (const toml::node* e : nodes) {
      const std::string name = stringOf(*e, what);
      if (std::find(accepted.begin(), accepted.end(), name) == accepted.end())
        fail(*e,
             what + ": unknown " + family + " '" + name + "' (accepted: " + listed(accepted) + ")");
      out.push_back(name);
    }
    checkDistinct(out, nodes, what);
    return out;
  }

  /// Strategy specs (`paper`, `paper:extra_layers=1`) of one family, checked by its registry.
  template <class Factory>
  std::vector<std::string> specs(const toml::node& node, const std::string& what,
                                 const Registry<Factory>& registry) const {
    const auto nodes = elements(node, what);
    std::vector<std::string> out;
    for (const toml::node* e : nodes) {
      const std::string spec = stringOf(*e, what);
      try {
        registry.parse(spec);
      } catch (const UsageError& error) {
        fail(*e, what + ": " + error.what());
      }
      out.push_back(spec);
    }
    checkDistinct(out, nodes, what);
    return out;
  }

  template <class T>
  std::vector<T> integers(const toml::node& node, const std::string& what, std::int64_t lo,
                          std::int64_t hi) const {
    const auto nodes = elements(node, what);
    std::vector<T> out;
    for (const toml::node* e : nodes) out.push_back(static_cast<T>(integerOf(*e, what, lo, hi)));
    checkDistinct(out, nodes, what);
    return out;
  }

  std::vector<int> depthsOf(const toml::node& node, const std::string& what) const {
    return integers<int>(node, what, kMinDepth, kMaxDepth);
  }
  std::vector<std::uint64_t> seedsOf(const toml::node& node, const std::string& what) const {
    return integers<std::uint64_t>(node, what, 0, std::numeric_limits<std::int64_t>::max());
  }

  GridFields readGrid(const toml::table& t, const std::string& prefix) const {
    GridFields g;
    if (const toml::node* n = t.get("problems")) g.problems = problemsOf(*n, prefix + "problems");
    if (const toml::node* n = t.get("bounding"))
      g.bounding = specs(*n, prefix + "bounding", boundingRegistry());
    if (const toml::node* n = t.get("subdivision"))
      g.subdivision = specs(*n, prefix + "subdivision", subdivisionRegistry());
    if (const toml::node* n = t.get("projection"))
      g.projection = specs(*n, prefix + "projection", projectionRegistry());
    if (const toml::node* n = t.get("classification"))
      g.classification = specs(*n, prefix + "classification", classificationRegistry());
    if (const toml::node* n = t.get("connection"))
      g.connection = specs(*n, prefix + "connection", connectionRegistry());
    if (const toml::node* n = t.get("scalar"))
      g.scalar = names(*n, prefix + "scalar", kScalarNames, "scalar type");
    if (const toml::node* n = t.get("precision")) {
      g.precision = integers<unsigned>(*n, prefix + "precision", kMinPrecision, kMaxPrecision);
      g.precisionNode = n;
    }
    if (const toml::node* n = t.get("depths")) g.depths = depthsOf(*n, prefix + "depths");
    if (const toml::node* n = t.get("seeds")) g.seeds = seedsOf(*n, prefix + "seeds");
    if (const toml::node* n = t.get("timeout_s")) {
      double v = 0;
      if (const auto* i = n->as_integer())
        v = static_cast<double>(i->get());
      else if (const auto* f = n->as_floating_point())
        v = f->get();
      else
        fail(*n, prefix + "timeout_s must be a number, not " + tomlTypeName(*n));
      if (!(v > 0 && v <= kMaxTimeoutS))
        fail(*n,
             prefix + "timeout_s must be positive and at most " + jsonNumber(kMaxTimeoutS) + " s");
      g.timeout = v;
    }
    return g;
  }

  std::vector<ProblemEntry> problemsOf(const toml::node& node, const std::string& what) const {
    std::vector<ProblemEntry> entries;
    for (const toml::node* e : elements(node, what)) {
      ProblemEntry entry;
      entry.node = e;
      if (e->is_string()) {
        entry.problems = files(*e, e->as_string()->get());
      } else if (const toml::table* t = e->as_table()) {
        if (t->get("generator"))
          generated(*t, entry);
        else if (t->get("file"))
          fileEntry(*t, entry);
        else
          fail(*e, what + ": a problem table needs 'file' or 'generator'");
      } else {
        fail(*e,
             what + " must hold problem file paths (strings) or tables, not " + tomlTypeName(*e));
      }
      entries.push_back(std::move(entry));
    }
    return entries;
  }

  void fileEntry(const toml::table& t, ProblemEntry& entry) const {
    for (auto&& [key, node] : t) {
      const std::string k(key.str());
      if (k == "file")
        entry.problems = files(node, stringOf(node, "file"));
      else if (k == "depths")
        entry.depths = depthsOf(node, "depths");
      else if (k == "jitter")
        entry.jitter = seedsOf(node, "jitter");
      else
        fail(key.source(), "unknown key '" + k +
                               "' in a problem file entry (known: file, "
                               "depths, jitter)");
    }
  }

  void generated(const toml::table& t, ProblemEntry& entry) const {
    std::string generator;
    std::vector<int> dimensions;
    std::vector<std::uint64_t> seeds = {0};
    const toml::node& g = *t.get("generator");
    generator = stringOf(g, "generator");
    const int minN = generatorMinDimension(generator);
    if (minN == 0)
      fail(g, "unknown generator '" + generator + "' (accepted: " + listed(kGeneratorNames) + ")");
    for (auto&& [key, node] : t) {
      const std::string k(key.str());
      if (k == "generator") {
      } else if (k == "n") {
        dimensions = integers<int>(node, "n", minN, kMaxGeneratedDimension);
      } else if (k == "seeds") {
        // A count (seeds 0..count-1) or a list of seeds.
        if (node.is_integer())
          seeds.resize(integerOf(node, "seeds", 1, kMaxGeneratorSeeds));
        else
          seeds = seedsOf(node, "seeds");
        if (node.is_integer())
          for (std::size_t i = 0; i < seeds.size(); ++i) seeds[i] = i;
        else if (static_cast<std::int64_t>(seeds.size()) > kMaxGeneratorSeeds)
          fail(node, "seeds: at most " + std::to_string(kMaxGeneratorSeeds) + " seeds");
      } else if (k == "depths") {
        entry.depths = depthsOf(node, "depths");
      } else if (k == "jitter") {
        entry.jitter = seedsOf(node, "jitter");
      } else {
        fail(key.source(), "unknown key '" + k +
                               "' in a generated problem entry (known: "
                               "generator, n, seeds, depths, jitter)");
      }
    }
    if (dimensions.empty()) fail(g, "a generated problem entry needs 'n'");
    for (int n : dimensions)
      for (std::uint64_t seed : seeds) {
        const GeneratedProblem gp = generateProblem(generator, n, seed);
        const Problem p = parseProblem(gp.text, gp.name + ".toml");
        ExperimentProblem e;
        e.name = p.name;
        e.generatedText = gp.text;
        e.n = p.n();
        e.k = p.k();
        e.expect = p.expect;
        entry.problems.push_back(std::move(e));
      }
  }

  /// The problem files of a path or a glob (`*` and `?` in the file name only), loaded and
  /// validated.
  std::vector<ExperimentProblem> files(const toml::node& node, const std::string& pattern) const {
    if (pattern.empty()) fail(node, "empty problem file path");
    const fs::path written(pattern);
    const fs::path full = written.is_absolute() ? written : root_ / written;
    std::vector<std::pair<std::string, fs::path>> found;  // recorded path, actual path
    const std::string name = written.filename().string();
    if (name.find_first_of("*?[") != std::string::npos) {
      if (written.parent_path().string().find_first_of("*?[") != std::string::npos)
        fail(node, "'" + pattern + "': only the file name may hold * or ?");
      std::error_code ec;
      const fs::path dir = full.parent_path();
      if (!fs::is_directory(dir, ec))
        fail(node, "'" + pattern + "': no such directory " + dir.string());
      for (const auto& f : fs::directory_iterator(dir, ec)) {
        const std::string leaf = f.path().filename().string();
        if (f.is_regular_file(ec) && ::fnmatch(name.c_str(), leaf.c_str(), FNM_PERIOD) == 0)
          found.emplace_back((written.parent_path() / leaf).generic_string(), f.path());
      }
      std::sort(found.begin(), found.end());
      if (found.empty()) fail(node, "'" + pattern + "' matches no file in " + dir.string());
    } else {
      std::error_code ec;
      if (!fs::is_regular_file(full, ec))
        fail(node, "no such problem file '" + pattern + "' (" + full.string() + ")");
      found.emplace_back(written.generic_string(), full);
    }
    std::vector<ExperimentProblem> out;
    for (const auto& [recorded, actual] : found) {
      const Problem p = loadProblem(actual);
      ExperimentProblem e;
      e.name = p.name;
      e.file = recorded;
      e.path = actual;
      e.n = p.n();
      e.k = p.k();
      e.expect = p.expect;
      out.push_back(std::move(e));
    }
    return out;
  }

  /// Applies `over` to `base` and the defaults, and checks the keys against each other.
  void finish(ExperimentConfig& c, GridFields base, const GridFields& over) const {
    if (over.problems) base.problems = over.problems;
    if (over.bounding) base.bounding = over.bounding;
    if (over.subdivision) base.subdivision = over.subdivision;
    if (over.projection) base.projection = over.projection;
    if (over.classification) base.classification = over.classification;
    if (over.connection) base.connection = over.connection;
    if (over.scalar) base.scalar = over.scalar;
    if (over.precision) {
      base.precision = over.precision;
      base.precisionNode = over.precisionNode;
    }
    if (over.depths) base.depths = over.depths;
    if (over.seeds) base.seeds = over.seeds;
    if (over.timeout) base.timeout = over.timeout;

    const Settings defaults;
    c.bounding = base.bounding.value_or(std::vector<std::string>{defaults.bounding});
    c.subdivision = base.subdivision.value_or(std::vector<std::string>{defaults.subdivision});
    c.projection = base.projection.value_or(std::vector<std::string>{defaults.projection});
    c.classification =
        base.classification.value_or(std::vector<std::string>{defaults.classification});
    c.connection = base.connection.value_or(std::vector<std::string>{defaults.connection});
    c.scalar = base.scalar.value_or(std::vector<std::string>{defaults.scalar});
    const bool mpfr = std::find(c.scalar.begin(), c.scalar.end(), "mpfr") != c.scalar.end();
    if (base.precision && !mpfr)
      fail(*base.precisionNode, "precision applies to scalar \"mpfr\" only, which is not listed");
    if (mpfr) c.precision = base.precision.value_or(std::vector<unsigned>{kDefaultMpfrPrecision});
    c.depths = *base.depths;
    c.seeds = base.seeds.value_or(std::vector<std::uint64_t>{});
    c.timeoutS = base.timeout.value_or(600);

    std::map<std::string, std::string> seen;  // problem name -> where it came from
    for (const ProblemEntry& entry : *base.problems) {
      for (ExperimentProblem p : entry.problems) {
        p.depths = entry.depths.value_or(c.depths);
        const std::vector<std::uint64_t> seeds = entry.jitter.value_or(c.seeds);
        p.jitter.clear();
        for (std::uint64_t s : seeds) p.jitter.emplace_back(s);
        if (p.jitter.empty()) p.jitter.emplace_back(std::nullopt);
        const std::string from = p.file.empty() ? "generated" : p.file;
        if (seen.count(p.name))
          fail(*entry.node, "problem name '" + p.name + "' appears twice (" + seen[p.name] +
                                " and " + from + "): run names would collide");
        seen[p.name] = from;
        c.problems.push_back(std::move(p));
      }
    }
    std::size_t runs = 0;
    std::size_t perProblem = c.bounding.size() * c.subdivision.size() * c.projection.size() *
                             c.classification.size() * c.connection.size() *
                             (c.scalar.size() - (mpfr ? 1 : 0) + (mpfr ? c.precision.size() : 0));
    for (const ExperimentProblem& p : c.problems)
      runs += perProblem * p.depths.size() * p.jitter.size();
    if (runs > kMaxRuns)
      fail(*base.problems->front().node, "the grid has " + std::to_string(runs) +
                                             " runs; at most " + std::to_string(kMaxRuns) +
                                             " are supported");
  }

  std::string file_;
  const std::string& text_;
  fs::path root_;
};

}  // namespace

ExperimentConfig loadExperimentConfig(const fs::path& file, bool quick) {
  const std::string name = file.string();
  const std::string text = readInputFile(file, "experiment config");
  checkTomlText(text, name);
  const toml::table top = parseTomlText(text, name);
  return ConfigReader(file, text).run(top, quick);
}

std::vector<ExperimentRun> experimentGrid(const ExperimentConfig& c) {
  std::vector<ExperimentRun> runs;
  for (std::size_t p = 0; p < c.problems.size(); ++p) {
    const ExperimentProblem& problem = c.problems[p];
    for (const std::string& bounding : c.bounding)
      for (const std::string& subdivision : c.subdivision)
        for (const std::string& projection : c.projection)
          for (const std::string& classification : c.classification)
            for (const std::string& connection : c.connection)
              for (const std::string& scalar : c.scalar) {
                const std::vector<unsigned> bits =
                    scalar == "double" ? std::vector<unsigned>{53} : c.precision;
                for (unsigned precision : bits)
                  for (int depth : problem.depths)
                    for (const std::optional<std::uint64_t>& jitter : problem.jitter) {
                      ExperimentRun run;
                      run.problem = p;
                      Settings& s = run.settings;
                      s.depth = depth;
                      s.bounding = bounding;
                      s.subdivision = subdivision;
                      s.scalar = scalar;
                      s.precisionBits = precision;
                      s.projection = projection;
                      s.classification = classification;
                      s.connection = connection;
                      s.jitter = jitter;
                      run.id = problem.name + ".L" + std::to_string(depth) + "." +
                               idPart(bounding) + "." + idPart(subdivision) + "." +
                               idPart(projection) + "." + idPart(classification) + "." +
                               idPart(connection) + "." + scalar + std::to_string(precision) +
                               (jitter ? ".j" + std::to_string(*jitter) : "");
                      runs.push_back(std::move(run));
                    }
              }
  }
  return runs;
}

// --- JSON numbers ----------------------------------------------------------------------------

namespace {

/// A recursive-descent reader of the JSON that summary.json holds, collecting numbers.
class JsonFlattener {
 public:
  explicit JsonFlattener(std::string_view text) : s_(text) {}

  std::vector<std::pair<std::string, std::string>> run() {
    value("", 0);
    space();
    if (i_ != s_.size()) error("text after the JSON value");
    return std::move(out_);
  }

 private:
  [[noreturn]] void error(const std::string& what) const {
    throw std::runtime_error("malformed JSON at byte " + std::to_string(i_) + ": " + what);
  }
  void space() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\n' || s_[i_] == '\r' || s_[i_] == '\t'))
      ++i_;
  }
  bool take(char c) {
    space();
    if (i_ < s_.size() && s_[i_] == c) {
      ++i_;
      return true;
    }
    return false;
  }
  void expect(char c) {
    if (!take(c)) error(std::string("expected '") + c + "'");
  }
  std::string string() {
    expect('"');
    std::string out;
    while (i_ < s_.size() && s_[i_] != '"') {
      if (s_[i_] == '\\') {
        if (++i_ >= s_.size()) break;
        // Escapes are kept loosely: only key names and skipped strings use them.
        out += s_[i_] == 'u' ? '?' : s_[i_];
        if (s_[i_] == 'u') i_ += 4;
        ++i_;
      } else {
        out += s_[i_++];
      }
    }
    if (i_ >= s_.size()) error("unterminated string");
    ++i_;
    return out;
  }
  void value(const std::string& path, int depth) {
    if (depth > 64) error("nested too deeply");
    space();
    if (i_ >= s_.size()) error("unexpected end");
    const char c = s_[i_];
    if (c == '{') {
      ++i_;
      if (take('}')) return;
      do {
        space();
        const std::string key = string();
        expect(':');
        value(path.empty() ? key : path + "." + key, depth + 1);
      } while (take(','));
      expect('}');
    } else if (c == '[') {
      ++i_;
      if (take(']')) return;
      int index = 0;
      do value(path + "." + std::to_string(index++), depth + 1);
      while (take(','));
      expect(']');
    } else if (c == '"') {
      string();
    } else if (s_.substr(i_, 4) == "true") {
      i_ += 4;
    } else if (s_.substr(i_, 5) == "false") {
      i_ += 5;
    } else if (s_.substr(i_, 4) == "null") {
      i_ += 4;
      out_.emplace_back(path, "");
    } else {
      const std::size_t start = i_;
      while (i_ < s_.size() && std::strchr("+-0123456789.eE", s_[i_])) ++i_;
      const std::string number(s_.substr(start, i_ - start));
      char* end = nullptr;
      if (number.empty()) error("unexpected character");
      std::strtod(number.c_str(), &end);
      if (end != number.c_str() + number.size()) error("bad number '" + number + "'");
      out_.emplace_back(path, number);
    }
  }

  std::string_view s_;
  std::size_t i_ = 0;
  std::vector<std::pair<std::string, std::string>> out_;
};

}  // namespace

std::vector<std::pair<std::string, std::string>> flattenJsonNumbers(std::string_view json) {
  return JsonFlattener(json).run();
}

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

std::string trimmed(std::string s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
  std::size_t start = 0;
  while (start < s.size() && std::isspace(static_cast<unsigned char>(s[start]))) ++start;
  return s.substr(start);
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

std::string utcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  ::gmtime_r(&now, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buffer;
}

/// Counts of one invocation, for the report and the provenance.
struct Tally {
  std::size_t total = 0, ran = 0, skipped = 0, failed = 0;
  std::vector<std::string> failedRuns;
};

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
    << ", \"timeout_s\": " << jsonNumber(c.timeoutS) << "},\n"
    << "  \"runs\": {\"total\": " << tally.total << ", \"ran\": " << tally.ran
    << ", \"skipped\": " << tally.skipped << ", \"failed\": " << tally.failed
    << ", \"failed_runs\": " << jsonArray(tally.failedRuns) << ", \"jobs\": " << o.jobs << "},\n"
    << "  \"date\": " << jsonQuoted(started) << ",\n"
    << "  \"finished\": " << jsonQuoted(utcNow()) << ",\n"
    << "  \"machine\": {\"hostname\": " << jsonQuoted(host)
    << ", \"nproc\": " << std::max(1u, std::thread::hardware_concurrency())
    << ", \"cpu_model\": " << jsonQuoted(procField("/proc/cpuinfo", "model name"))
    << ", \"memory_bytes\": " << memoryBytes << "}\n}\n";
  return j.str();
}

}  // namespace

// --- Runner ----------------------------------------------------------------------------------

namespace {

using Clock = std::chrono::steady_clock;

/// What became of one run.
struct Outcome {
  std::string status;  ///< ok, failed, timeout, crashed, error
  std::optional<int> exitCode;
  std::string error;
  bool skipped = false;
  double seconds = 0;
  std::vector<std::pair<std::string, std::string>> values;  ///< summary.json numbers
};

volatile std::sig_atomic_t gInterrupted = 0;
void onInterrupt(int signal) { gInterrupted = signal; }

/// Stops child processes: SIGTERM first, so that a solve removes its staging folder and leaves
/// its run directory whole, then SIGKILL for any still running after a second. Returns each
/// child's wait status, in the order given.
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

/// The outcome of a child that ended with wait status `status` (or was killed on timeout).
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

/// The arguments of `ndcontour solve` for one run (without the program name).
std::vector<std::string> solveArguments(const std::string& problem, const std::string& runDir,
                                        const Settings& s) {
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
  if (s.maxMemoryBytes > 0) {
    a.push_back("--max-memory");
    a.push_back(std::to_string(s.maxMemoryBytes));
  }
  a.push_back("--json");
  return a;
}

/// Starts a run: standard input and output /dev/null, standard error into the run directory.
/// Returns the pid, or -1 with `error` set.
pid_t spawnRun(const std::string& executable, const std::vector<std::string>& arguments,
               const fs::path& stderrFile, std::string& error) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
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

/// Progress on standard error: a redrawn bar on a terminal, else one line per finished run.
class ProgressReport {
 public:
  ProgressReport(std::size_t total, std::size_t done, std::size_t failed)
      : tty_(::isatty(STDERR_FILENO) == 1),
        total_(total),
        done_(done),
        failed_(failed),
        start_(Clock::now()) {}

  void finished(const std::string& run, const Outcome& o) {
    ++done_;
    ++ran_;
    if (o.status != "ok") ++failed_;
    if (tty_) {
      if (o.status != "ok") {
        std::fprintf(stderr, "\r\033[K%s: %s: %s\n", run.c_str(), o.status.c_str(),
                     o.error.c_str());
      }
      draw();
    } else {
      std::fprintf(stderr, "[%zu/%zu] %s %.2f s %s%s%s\n", done_, total_, o.status.c_str(),
                   o.seconds, run.c_str(), o.error.empty() ? "" : ": ", o.error.c_str());
    }
    std::fflush(stderr);
  }

  /// Redraws the bar (terminal only) at most five times a second.
  void tick() {
    if (!tty_ || Clock::now() - lastDraw_ < std::chrono::milliseconds(200)) return;
    draw();
  }

  void end() {
    if (tty_) std::fputs("\n", stderr);
    std::fflush(stderr);
  }

 private:
  void draw() {
    lastDraw_ = Clock::now();
    const int width = 30;
    const int filled = total_ ? static_cast<int>(width * done_ / total_) : width;
    std::string bar(filled, '#');
    bar.resize(width, '.');
    std::string eta = "eta ?";
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    if (ran_ > 0)
      eta = "eta " + std::to_string(static_cast<long>(elapsed / ran_ * (total_ - done_) + 0.5)) +
            " s";
    std::fprintf(stderr, "\r[%s] %zu/%zu runs, %zu failed, %s\033[K", bar.c_str(), done_, total_,
                 failed_, eta.c_str());
    std::fflush(stderr);
  }

  bool tty_;
  std::size_t total_, done_, failed_, ran_ = 0;
  Clock::time_point start_, lastDraw_{};
};

/// The `expect_ok` and `expect_notes` columns of a run: the problem's `[expect]` compared with
/// the mesh of its summary by checkExpectation, as `solve` does (recomputed here, so summaries
/// of earlier invocations get them too). `expect_ok` is `true` or `false` (a compared key
/// differs; empty when no key could be compared), `expect_notes` lists the keys that differ or
/// could not be compared; both are empty when the problem has no `[expect]` or the run has no
/// summary.
std::pair<std::string, std::string> expectationColumns(const ExperimentProblem& p,
                                                       const Outcome& o) {
  const Expectation& x = p.expect;
  if (o.status != "ok" || (!x.components && !x.eulerCharacteristic && x.other.empty())) return {};
  const std::map<std::string, std::string> values(o.values.begin(), o.values.end());
  MeshStats m;
  const std::pair<const char*, std::int64_t*> fields[] = {
      {"mesh.vertices", &m.vertices},
      {"mesh.edges", &m.edges},
      {"mesh.triangles", &m.triangles},
      {"mesh.components", &m.components},
      {"mesh.boundary_edges", &m.boundaryEdges},
      {"mesh.nonmanifold_edges", &m.nonmanifoldEdges},
      {"mesh.euler_characteristic", &m.eulerCharacteristic},
      {"mesh.open_ends", &m.openEnds},
      {"mesh.branch_vertices", &m.branchVertices}};
  for (const auto& [name, field] : fields) {
    const auto it = values.find(name);
    if (it == values.end() || it->second.empty()) return {};
    try {
      *field = std::stoll(it->second);
    } catch (const std::exception&) {
      return {};
    }
  }
  // Newer than the other fields: a summary written before it cannot be compared on it.
  if (const auto it = values.find("mesh.boundary_components");
      it != values.end() && !it->second.empty()) {
    m.boundaryComponents = std::stoll(it->second);
  } else if (x.other.count("boundary_components")) {
    return {};
  }
  const std::vector<ExpectCheck> checks = checkExpectation(x, m, p.k);
  std::string notes;
  bool compared = false;
  for (const ExpectCheck& check : checks) {
    compared = compared || check.notComparable.empty();
    if (!check.ok) notes += (notes.empty() ? "" : "; ") + describeCheck(check);
  }
  if (!compared) return {"", notes};
  return {expectationMismatch(checks) ? "false" : "true", notes};
}

void writeCsv(const fs::path& file, const ExperimentConfig& c,
              const std::vector<ExperimentRun>& runs, const std::vector<Outcome>& outcomes) {
  // Columns: the run's identity, then the known summary numbers, then any others (sorted).
  std::vector<std::string> columns(kExperimentSummaryColumns.begin(),
                                   kExperimentSummaryColumns.end());
  // A list element has a number in its path (`diagnostics.singular_points.0.sigma_min`): lists
  // vary in length from run to run and stay in the run's files.
  const auto listElement = [](const std::string& name) {
    std::istringstream parts(name);
    for (std::string part; std::getline(parts, part, '.');)
      if (!part.empty() && std::all_of(part.begin(), part.end(),
                                       [](unsigned char ch) { return std::isdigit(ch) != 0; }))
        return true;
    return false;
  };
  std::set<std::string> extra;
  for (const Outcome& o : outcomes)
    for (const auto& [name, value] : o.values)
      if (name != "n" && name != "k" && name.rfind("settings.", 0) != 0 &&
          name.rfind("expect.", 0) != 0 && !listElement(name) &&
          std::find(columns.begin(), columns.end(), name) == columns.end())
        extra.insert(name);
  columns.insert(columns.end(), extra.begin(), extra.end());

  std::ostringstream csv;
  for (std::size_t i = 0; i < kExperimentRunColumns.size(); ++i)
    csv << (i ? "," : "") << kExperimentRunColumns[i];
  for (const std::string& name : columns) csv << ',' << name;
  csv << '\n';
  const auto optional = [](const auto& v) { return v ? std::to_string(*v) : std::string(); };
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const ExperimentRun& run = runs[r];
    const ExperimentProblem& p = c.problems[run.problem];
    const Settings& s = run.settings;
    const Outcome& o = outcomes[r];
    const auto [expectOk, expectNotes] = expectationColumns(p, o);
    const std::vector<std::string> fields = {c.id,
                                             run.id,
                                             p.name,
                                             p.file,
                                             std::to_string(p.n),
                                             std::to_string(p.k),
                                             std::to_string(s.depth),
                                             optional(s.jitter),
                                             s.scalar,
                                             std::to_string(s.precisionBits),
                                             s.bounding,
                                             s.subdivision,
                                             s.projection,
                                             s.classification,
                                             s.connection,
                                             o.status,
                                             optional(o.exitCode),
                                             o.error,
                                             optional(p.expect.components),
                                             optional(p.expect.eulerCharacteristic),
                                             expectOk,
                                             expectNotes};
    for (std::size_t i = 0; i < fields.size(); ++i) csv << (i ? "," : "") << csvField(fields[i]);
    const std::map<std::string, std::string> values(o.values.begin(), o.values.end());
    for (const std::string& name : columns) {
      const auto it = values.find(name);
      csv << ',' << (it == values.end() ? "" : csvField(it->second));
    }
    csv << '\n';
  }
  writeAtomically(file, csv.str());
}

/// Restores the previous SIGINT and SIGTERM handlers at scope exit.
class InterruptScope {
 public:
  InterruptScope() {
    gInterrupted = 0;
    struct sigaction action {};
    action.sa_handler = onInterrupt;
    sigemptyset(&action.sa_mask);
    ::sigaction(SIGINT, &action, &savedInt_);
    ::sigaction(SIGTERM, &action, &savedTerm_);
  }
  ~InterruptScope() {
    ::sigaction(SIGINT, &savedInt_, nullptr);
    ::sigaction(SIGTERM, &savedTerm_, nullptr);
  }

 private:
  struct sigaction savedInt_ {
  }, savedTerm_{};
};

/// Generated problems become files beside the results, so that each run can be repeated with
/// `ndcontour solve`; an identical existing file is left alone.
void writeGeneratedProblems(ExperimentConfig& config, const fs::path& dir) {
  std::error_code ec;
  for (ExperimentProblem& p : config.problems) {
    if (p.generatedText.empty()) continue;
    fs::create_directories(dir / "problems", ec);
    p.path = dir / "problems" / (p.name + ".toml");
    p.file = p.path.generic_string();
    if (!fs::exists(p.path, ec) || readFile(p.path) != p.generatedText)
      writeAtomically(p.path, p.generatedText);
  }
}

/// Resume: a run whose folder has a summary finished before; its outcome is read back. Returns
/// the runs still to do, in grid order.
std::vector<std::size_t> resumeFinished(const std::vector<ExperimentRun>& runs,
                                        const fs::path& runsDir, std::vector<Outcome>& outcomes,
                                        Tally& tally) {
  std::error_code ec;
  std::vector<std::size_t> pending;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const fs::path runDir = runsDir / runs[i].id;
    if (fs::exists(runDir / "summary.json", ec)) {
      outcomes[i] = readSummary(runDir);
      outcomes[i].skipped = true;
      ++tally.skipped;
    } else {
      pending.push_back(i);
    }
  }
  return pending;
}

/// Runs the pending runs as child processes, `jobs` at once, each within the timeout, until
/// all finished or SIGINT / SIGTERM arrives.
class Scheduler {
 public:
  Scheduler(const ExperimentConfig& config, const ExperimentOptions& options,
            const std::vector<ExperimentRun>& runs, const fs::path& runsDir,
            std::vector<Outcome>& outcomes, ProgressReport& progress)
      : config_(config),
        options_(options),
        runs_(runs),
        runsDir_(runsDir),
        outcomes_(outcomes),
        progress_(progress),
        jobs_(std::max(1, options.jobs)) {}

  /// Runs `pending`; on an interrupt the children still running are stopped.
  void run(const std::vector<std::size_t>& pending) {
    std::size_t next = 0;
    {
      InterruptScope interrupts;
      while ((next < pending.size() || !running_.empty()) && !gInterrupted) {
        // Start runs in grid order while there is room.
        while (static_cast<int>(running_.size()) < jobs_ && next < pending.size() && !gInterrupted)
          start(pending[next++]);
        if (!collect()) {
          std::this_thread::sleep_for(std::chrono::milliseconds(5));
          progress_.tick();
        }
      }
    }
    if (!gInterrupted) return;
    std::vector<pid_t> pids;
    for (const Child& child : running_) pids.push_back(child.pid);
    stopChildren(pids);
  }

 private:
  struct Child {
    pid_t pid;
    std::size_t run;
    Clock::time_point start;
  };

  /// Starts run i (its folder, its command.txt, the child), or records why it could not.
  void start(std::size_t i) {
    const ExperimentRun& run = runs_[i];
    const ExperimentProblem& p = config_.problems[run.problem];
    const fs::path runDir = runsDir_ / run.id;
    std::string error;
    pid_t pid = -1;
    try {
      std::error_code ec;
      fs::create_directories(runDir, ec);
      if (ec) throw InputError(runDir.string() + ": cannot create the run directory");
      // The command that repeats this run by hand, from the repository root.
      std::string command = "ndcontour";
      for (const std::string& a : solveArguments(p.file, runDir.string(), run.settings))
        command += " " + shellWord(a);
      writeAtomically(runDir / "command.txt", command + "\n");
      // Children that run at once share the machine's memory budget.
      Settings shared = run.settings;
      shared.maxMemoryBytes = std::max<std::uint64_t>(defaultMemoryBudget() / jobs_, 1u << 30);
      pid = spawnRun(options_.executable, solveArguments(p.path.string(), runDir.string(), shared),
                     runDir / "stderr.txt", error);
    } catch (const std::exception& e) {
      error = e.what();
    }
    if (pid < 0) {
      outcomes_[i].status = "error";
      outcomes_[i].error = oneLine(error);
      progress_.finished(run.id, outcomes_[i]);
      return;
    }
    running_.push_back({pid, i, Clock::now()});
  }

  /// Collects finished children and kills those past the timeout; whether any ended.
  bool collect() {
    bool changed = false;
    for (auto it = running_.begin(); it != running_.end();) {
      int status = 0;
      const pid_t got = ::waitpid(it->pid, &status, WNOHANG);
      const double elapsed = std::chrono::duration<double>(Clock::now() - it->start).count();
      bool timedOut = false;
      if (got == 0 && elapsed > config_.timeoutS) {
        status = stopChildren({it->pid}).front();
        timedOut = true;
      } else if (got == 0 || (got < 0 && errno == EINTR)) {
        ++it;
        continue;
      }
      Outcome o;
      if (got < 0 && !timedOut) {
        o.status = "error";
        o.error = std::string("lost the child process: ") + std::strerror(errno);
      } else {
        o = outcomeOf(runsDir_ / runs_[it->run].id, status, timedOut, config_.timeoutS);
      }
      o.seconds = elapsed;
      outcomes_[it->run] = o;
      progress_.finished(runs_[it->run].id, o);
      it = running_.erase(it);
      changed = true;
    }
    return changed;
  }

  const ExperimentConfig& config_;
  const ExperimentOptions& options_;
  const std::vector<ExperimentRun>& runs_;
  const fs::path& runsDir_;
  std::vector<Outcome>& outcomes_;
  ProgressReport& progress_;
  const int jobs_;
  std::vector<Child> running_;
};

/// The combined CSV, the provenance and the closing lines on standard output; the exit status.
int finishExperiment(const ExperimentConfig& config, const ExperimentOptions& options,
                     const std::vector<ExperimentRun>& runs, const std::vector<Outcome>& outcomes,
                     Tally& tally, const fs::path& dir, const std::string& started) {
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!outcomes[i].skipped) ++tally.ran;
    if (outcomes[i].status != "ok") {
      ++tally.failed;
      tally.failedRuns.push_back(runs[i].id);
    }
  }
  const fs::path csv = dir / (config.id + ".csv");
  writeCsv(csv, config, runs, outcomes);
  writeAtomically(dir / "provenance.json", provenanceJson(config, options, tally, started));

  std::printf("experiment %s: %zu runs: %zu ran, %zu skipped (finished before), %zu failed\n",
              config.id.c_str(), tally.total, tally.ran, tally.skipped, tally.failed);
  for (std::size_t i = 0; i < runs.size(); ++i)
    if (outcomes[i].status != "ok")
      std::printf("  failed: %s: %s%s%s\n", runs[i].id.c_str(), outcomes[i].status.c_str(),
                  outcomes[i].error.empty() ? "" : ": ", outcomes[i].error.c_str());
  std::printf("wrote %s and %s\n", csv.string().c_str(),
              (dir / "provenance.json").string().c_str());
  std::fflush(stdout);
  return tally.failed ? 1 : 0;
}

}  // namespace

int runExperiment(ExperimentConfig config, const ExperimentOptions& options) {
  const std::string started = utcNow();
  const fs::path dir = options.outDir / config.id;
  const fs::path runsDir = dir / "runs";
  std::error_code ec;
  fs::create_directories(runsDir, ec);
  if (ec || !fs::is_directory(runsDir, ec))
    throw InputError(runsDir.string() + ": cannot create the output directory");
  writeGeneratedProblems(config, dir);

  const std::vector<ExperimentRun> runs = experimentGrid(config);
  std::vector<Outcome> outcomes(runs.size());
  Tally tally;
  tally.total = runs.size();
  const std::vector<std::size_t> pending = resumeFinished(runs, runsDir, outcomes, tally);
  std::size_t failedBefore = 0;
  for (const Outcome& o : outcomes)
    if (o.skipped && o.status != "ok") ++failedBefore;
  std::fprintf(stderr, "experiment %s%s: %zu runs, %zu finished before, %d at once, timeout %s s\n",
               config.id.c_str(), config.quick ? " (quick)" : "", runs.size(), tally.skipped,
               std::max(1, options.jobs), jsonNumber(config.timeoutS).c_str());
  std::fflush(stderr);

  ProgressReport progress(runs.size(), tally.skipped, failedBefore);
  Scheduler(config, options, runs, runsDir, outcomes, progress).run(pending);
  progress.end();
  if (gInterrupted) {
    // Finished runs keep their summaries; the rest run on the next invocation.
    std::fprintf(stderr,
                 "experiment %s: interrupted; finished runs are kept and the next invocation "
                 "resumes\n",
                 config.id.c_str());
    return 128 + gInterrupted;
  }
  return finishExperiment(config, options, runs, outcomes, tally, dir, started);
}

}  // namespace ndc
