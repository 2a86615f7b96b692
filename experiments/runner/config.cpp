// Experiment configs (experiment.hpp, docs/experiments.md): their validation and the run grid.
#include "experiments/runner/experiment.hpp"

#include <fnmatch.h>

#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "applications/load.hpp"
#include "experiments/runner/generate.hpp"
#include "experiments/runner/runner_internal.hpp"
#include "framework/problem/toml_reader.hpp"
#include "framework/util/errors.hpp"
#include "pipeline/pipeline.hpp"
#include "strategies/bounding/bounding.hpp"
#include "strategies/classification/classification.hpp"
#include "strategies/connection/connection.hpp"
#include "strategies/projection/projection.hpp"
#include "strategies/subdivision/subdivision.hpp"

namespace ndc {
namespace fs = std::filesystem;
using runner_detail::jsonNumber;

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
        "id",         "artefact",  "description", "problems",       "bounding",   "subdivision",
        "connection", "scalar",    "precision",   "classification", "projection", "depths",
        "seeds",      "timeout_s", "cells",       "quick"};
    for (auto&& [key, node] : top)
      if (!kTopKeys.count(std::string(key.str())))
        fail(key.source(), "unknown key '" + std::string(key.str()) + "'" +
                               didYouMean(key.str(), {kTopKeys.begin(), kTopKeys.end()}) +
                               " (known: id, artefact, description, problems, bounding, "
                               "subdivision, connection, scalar, precision, classification, "
                               "projection, depths, seeds, timeout_s, cells, quick)");

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
    c.cells = cellsOf(top);

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
          fail(key.source(), "unknown key 'quick." + std::string(key.str()) + "'" +
                                 didYouMean(key.str(), {kQuickKeys.begin(), kQuickKeys.end()}) +
                                 " (known: problems, bounding, subdivision, connection, "
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

  /// `cells = true | false` (default false): whether the runs write cells.csv.
  bool cellsOf(const toml::table& top) const {
    const toml::node* node = top.get("cells");
    if (!node) return false;
    const auto* flag = node->as_boolean();
    if (!flag) fail(*node, "cells must be true or false, not " + tomlTypeName(*node));
    return flag->get();
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
        fail(key.source(), "unknown key '" + k + "' in a problem file entry" +
                               didYouMean(k, {"file", "depths", "jitter"}) +
                               " (known: file, depths, jitter)");
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
        fail(key.source(), "unknown key '" + k + "' in a generated problem entry" +
                               didYouMean(k, {"generator", "n", "seeds", "depths", "jitter"}) +
                               " (known: generator, n, seeds, depths, jitter)");
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

}  // namespace ndc
