// Strategy registries (framework/strategy/registry.hpp, docs/adding-a-strategy.md): specs and their
// errors, the docs table, and a test-only strategy registered from the test tree that the
// pipeline then runs like any other.
#include <catch2/catch.hpp>

#include <iostream>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "applications/load.hpp"
#include "framework/strategy/registry.hpp"
#include "pipeline/pipeline.hpp"
#include "strategies/bounding/bounding.hpp"
#include "strategies/classification/classification.hpp"
#include "strategies/connection/connection.hpp"
#include "strategies/projection/projection.hpp"
#include "strategies/subdivision/subdivision.hpp"
#include "tests/test_process.hpp"
#include "tests/test_support.hpp"

namespace {

using ndc::ParameterType;

/// A test-only classification: normal only when the projected point lies inside the cell
/// shrunk by `margin` of its width on every side (margin 0 is the paper's closed-box rule).
class MarginClassification {
 public:
  explicit MarginClassification(double margin) : margin_(margin) {}
  template <class S>
  ndc::CellClass classify(const ndc::Box<S>& cell, std::span<const S> point, bool converged) const {
    if (!converged) return ndc::CellClass::kFailed;
    for (int j = 0; j < cell.dim(); ++j) {
      const S inset = S(margin_) * (cell.hi[j] - cell.lo[j]);
      if (!(cell.lo[j] + inset <= point[j] && point[j] <= cell.hi[j] - inset))
        return ndc::CellClass::kAbnormal;
    }
    return ndc::CellClass::kNormal;
  }

 private:
  double margin_;
};

/// The registry line of the test-only model (registered once per test process).
void registerMarginClassification() {
  auto& registry = ndc::classificationRegistry();
  for (const std::string& name : registry.names())
    if (name == "test-margin") return;
  registry.add({{"test-margin",
                 "Test only: normal when the point lies inside the cell shrunk by a margin.",
                 {{"margin", ParameterType::kReal, 0, 0, 0.45, "share of the cell width"}}},
                [](const ndc::Parameters& p) {
                  return ndc::holdClassification(MarginClassification(p.real("margin")));
                }});
}

/// A test-only connection: the crossing connection's complex and record under other
/// capabilities, so that what the pipeline does can follow only from the capabilities.
class BorrowedCrossing {
 public:
  template <class S>
  ndc::ConnectionOutput<S> connect(const ndc::ConnectionInput<S>& input) const {
    return ndc::CrossingConnection{}.connect(input);
  }
};

/// Registers `name` as BorrowedCrossing with `capabilities` for the guard's lifetime (the tests
/// that loop over the connection family must not meet it).
class BorrowedCrossingGuard {
 public:
  BorrowedCrossingGuard(std::string name, ndc::Capabilities capabilities) : name_(std::move(name)) {
    ndc::connectionRegistry().add(
        {{name_, "Test only: the crossing connection under other capabilities.", {}, capabilities},
         [](const ndc::Parameters&) { return ndc::holdConnection(BorrowedCrossing{}); }});
  }
  ~BorrowedCrossingGuard() { ndc::connectionRegistry().remove(name_); }
  BorrowedCrossingGuard(const BorrowedCrossingGuard&) = delete;
  BorrowedCrossingGuard& operator=(const BorrowedCrossingGuard&) = delete;

 private:
  std::string name_;
};

/// The Markdown table of each family, without test-only models (test-margin).
std::vector<std::string> registryTables() {
  auto documented = [](std::vector<ndc::ModelSpec> models) {
    std::erase_if(models, [](const ndc::ModelSpec& m) { return m.name.rfind("test-", 0) == 0; });
    return models;
  };
  return {
      ndc::registryMarkdown("bounding", documented(ndc::boundingRegistry().specs())),
      ndc::registryMarkdown("subdivision", documented(ndc::subdivisionRegistry().specs())),
      ndc::registryMarkdown("projection", documented(ndc::projectionRegistry().specs())),
      ndc::registryMarkdown("classification", documented(ndc::classificationRegistry().specs())),
      ndc::registryMarkdown("connection", documented(ndc::connectionRegistry().specs()))};
}

const std::vector<ndc::ParameterSpec> kSpecs = {
    {"layers", ParameterType::kInteger, 1, 0, 8, "layers"},
    {"ratio", ParameterType::kReal, 0.5, 0, 1, "ratio"},
    {"thin", ParameterType::kBoolean, 1, 0, 1, "thin"}};

}  // namespace

TEST_CASE("registry: specs set parameters, defaults fill the rest", "[registry]") {
  const std::vector<ndc::ModelSpec> models = {{"alpha", "a", kSpecs}, {"beta", "b", {}}};
  const ndc::StrategyChoice plain = ndc::parseStrategySpec("alpha", "test", models);
  CHECK(plain.name == "alpha");
  CHECK(plain.parameters.integer("layers") == 1);
  CHECK(plain.parameters.json() == "{\"layers\": 1, \"ratio\": 0.5, \"thin\": true}");
  const ndc::StrategyChoice set =
      ndc::parseStrategySpec("alpha:thin=false,layers=8,ratio=0.25", "test", models);
  CHECK(set.parameters.integer("layers") == 8);
  CHECK(set.parameters.real("ratio") == 0.25);
  CHECK_FALSE(set.parameters.boolean("thin"));
  CHECK(set.parameters.text() == "layers=8,ratio=0.25,thin=false");
  CHECK(ndc::parseStrategySpec("beta", "test", models).parameters.json() == "{}");
  CHECK_THROWS_AS(plain.parameters.real("missing"), std::logic_error);
}

TEST_CASE("registry: bad specs are one-line usage errors naming what is wrong", "[registry]") {
  const std::vector<ndc::ModelSpec> models = {{"alpha", "a", kSpecs}, {"beta", "b", {}}};
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"gamma", "unknown test strategy 'gamma' (known: alpha, beta)"},
      {"", "unknown test strategy '' (known: alpha, beta)"},
      {"alpha:", "test strategy 'alpha:': no parameter after ':'"},
      {"alpha:layers", "test strategy 'alpha:layers': 'layers' is not KEY=VALUE"},
      {"alpha:=1", "test strategy 'alpha:=1': '=1' is not KEY=VALUE"},
      {"alpha:depth=1",
       "test strategy 'alpha:depth=1': unknown parameter 'depth' (known: layers, ratio, thin)"},
      {"beta:x=1", "test strategy 'beta:x=1': unknown parameter 'x' (it has none)"},
      {"alpha:layers=1,layers=2",
       "test strategy 'alpha:layers=1,layers=2': parameter 'layers' is given twice"},
      {"alpha:layers=9", "test strategy 'alpha:layers=9', layers: '9' is not an integer in 0..8"},
      {"alpha:layers=1.5",
       "test strategy 'alpha:layers=1.5', layers: '1.5' is not an integer in 0..8"},
      {"alpha:layers=", "test strategy 'alpha:layers=', layers: '' is not an integer in 0..8"},
      {"alpha:ratio=nan", "test strategy 'alpha:ratio=nan', ratio: 'nan' is not a number in 0..1"},
      {"alpha:ratio=2", "test strategy 'alpha:ratio=2', ratio: '2' is not a number in 0..1"},
      {"alpha:thin=yes", "test strategy 'alpha:thin=yes', thin: 'yes' is not true or false"},
      {"alpha:layers=1,", "test strategy 'alpha:layers=1,': '' is not KEY=VALUE"}};
  for (const auto& [spec, message] : bad) {
    INFO(spec);
    CHECK_THROWS_AS(ndc::parseStrategySpec(spec, "test", models), ndc::UsageError);
    CHECK_THROWS_WITH(ndc::parseStrategySpec(spec, "test", models), message);
  }
}

TEST_CASE("registry: a model name is registered once and is a valid name", "[registry]") {
  using Factory = int (*)(const ndc::Parameters&);
  ndc::Registry<Factory> registry("test", {{{"alpha", "a", {}}, nullptr}});
  CHECK_THROWS_AS(registry.add({{"alpha", "again", {}}, nullptr}), std::logic_error);
  CHECK_THROWS_AS(registry.add({{"Bad_Name", "b", {}}, nullptr}), std::logic_error);
  CHECK_THROWS_AS(registry.add({{"", "b", {}}, nullptr}), std::logic_error);
  registry.add({{"beta-2", "b", {}}, nullptr});
  CHECK(registry.names() == std::vector<std::string>{"alpha", "beta-2"});
  CHECK_THROWS_WITH(registry.find("gamma"), "unknown test strategy 'gamma' (known: alpha, beta-2)");
}

TEST_CASE("registry: the docs table of every family is the registry's", "[registry]") {
  // docs/adding-a-strategy.md lists the strategies; the table must be what the registries say.
  const std::string page =
      ndc::test::slurp(std::string(NDC_SOURCE_DIR) + "/docs/adding-a-strategy.md");
  REQUIRE(!page.empty());
  for (const std::string& table : registryTables()) {
    INFO("missing from docs/adding-a-strategy.md:\n" << table);
    CHECK(page.find(table) != std::string::npos);
  }
}

TEMPLATE_TEST_CASE(
    "registry: a test-only strategy registered in the test tree runs in the "
    "pipeline",
    "[registry]", NDC_SCALARS) {
  ndc::test::PrecisionScope<TestType> scope(128);
  const bool mpfr = !std::is_same_v<TestType, double>;
  registerMarginClassification();
  const ndc::Problem problem =
      ndc::loadProblem(std::string(NDC_SOURCE_DIR) + "/experiments/problems/sphere.toml");
  ndc::Settings settings;
  settings.depth = 4;
  settings.scalar = mpfr ? "mpfr" : "double";
  settings.precisionBits = mpfr ? 128 : 53;
  settings.connection = "paper";
  const ndc::Summary paper = ndc::runPipeline(problem, settings).summary;

  // margin 0 is the paper's closed-box rule: the same classes, the same mesh.
  settings.classification = "test-margin";
  const ndc::Summary same = ndc::runPipeline(problem, settings).summary;
  CHECK(same.settings.classification == "test-margin");
  CHECK(same.parameters.at(3) ==
        std::pair<std::string, std::string>{"classification", "{\"margin\": 0}"});
  CHECK(same.normal == paper.normal);
  CHECK(same.abnormal == paper.abnormal);
  CHECK(same.mesh.triangles == paper.mesh.triangles);

  // A margin turns normal cells whose points lie near a face abnormal, never the reverse.
  settings.classification = "test-margin:margin=0.25";
  const ndc::Summary strict = ndc::runPipeline(problem, settings).summary;
  CHECK(strict.solution == paper.solution);
  CHECK(strict.normal < paper.normal);
  CHECK(strict.abnormal > paper.abnormal);
  CHECK(strict.normal + strict.abnormal + strict.failed == strict.solution);
  CHECK(strict.parameters.at(3).second == "{\"margin\": 0.25}");

  settings.classification = "test-margin:margin=0.5";
  CHECK_THROWS_WITH(ndc::runPipeline(problem, settings),
                    "classification strategy 'test-margin:margin=0.5', margin: '0.5' is not a "
                    "number in 0..0.45");
}

TEST_CASE("registry: capabilities, not names, decide what the pipeline does with a model",
          "[registry]") {
  const BorrowedCrossingGuard certifyingModel(
      "test-certifying", {.certifies = true, .refines = true, .minK = 1, .maxK = 2});
  const BorrowedCrossingGuard curvesModel(
      "test-curves-only", {.certifies = false, .refines = false, .minK = 1, .maxK = 1});
  const std::string problems = std::string(NDC_SOURCE_DIR) + "/experiments/problems/";
  const ndc::Problem circle = ndc::loadProblem(problems + "circle.toml");
  ndc::Settings settings;
  settings.depth = 4;
  const ndc::Summary crossing = ndc::runPipeline(circle, settings).summary;
  REQUIRE(crossing.topology.certified);

  // A model that declares it certifies keeps its own record, whatever its name.
  settings.connection = "test-certifying";
  const ndc::Summary certifying = ndc::runPipeline(circle, settings).summary;
  CHECK(certifying.topology.certified);
  CHECK(certifying.topology.reason.empty());
  CHECK(certifying.mesh.vertices == crossing.mesh.vertices);

  // The same complex from a model that does not declare it is not called certified, and the
  // reason names the models that do.
  settings.connection = "test-curves-only";
  const ndc::Summary plain = ndc::runPipeline(circle, settings).summary;
  CHECK_FALSE(plain.topology.certified);
  CHECK(plain.topology.reason ==
        "the test-curves-only connection does not certify topology "
        "(crossing, test-certifying do)");
  CHECK(plain.mesh.vertices == crossing.mesh.vertices);

  // Its k range refuses a surface before any work, naming the models that build one.
  const ndc::Problem sphere = ndc::loadProblem(problems + "sphere.toml");
  CHECK_THROWS_WITH(ndc::runPipeline(sphere, settings),
                    Catch::Contains("the test-curves-only connection builds k = 1; this problem "
                                    "has k = 2 (n - m); use --connection paper, naive, crossing, "
                                    "test-certifying"));
}

// Prints the tables for docs/adding-a-strategy.md:
// build/bin/ndcontour_tests "[.registry-markdown]"
TEST_CASE("registry: print the docs tables", "[.registry-markdown]") {
  for (const std::string& table : registryTables()) std::cout << table << '\n';
}
