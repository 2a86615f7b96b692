// Problem files (docs/contracts.md 4.1): the example problems parse, and every class of bad input
// is an InputError on one line at the right file position.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include "applications/load.hpp"
#include "framework/problem/problem.hpp"
#include "tests/test_support.hpp"

namespace fs = std::filesystem;
using ndc::InputError;
using ndc::Problem;

namespace {

/// A valid problem text with replaceable parts; the equations are on line 4.
std::string problemText(const std::string& equations = R"(["x^2 + y^2 - 1"])",
                        const std::string& domain = "[[-2, 2], [-2, 2]]",
                        const std::string& variables = R"(["x", "y"])",
                        const std::string& extra = "") {
  return "name = \"p\"\nvariables = " + variables + "\ndomain = " + domain +
         "\nequations = " + equations + "\n" + extra;
}

/// The message of the InputError that parsing `text` throws, or "" if it parses.
std::string errorOf(const std::string& text) {
  try {
    ndc::parseProblem(text, "bad.toml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

/// Checks that `text` fails with a one-line message starting with `prefix` and holding `part`.
void checkError(const std::string& text, const std::string& prefix, const std::string& part) {
  const std::string message = errorOf(text);
  INFO("text:\n" << text << "\nmessage: " << message);
  REQUIRE(!message.empty());
  CHECK(message.find('\n') == std::string::npos);
  CHECK(message.rfind(prefix, 0) == 0);
  CHECK(message.find(part) != std::string::npos);
}

fs::path problemsDir() { return fs::path(ndc::test::sourceDir()) / "experiments" / "problems"; }

}  // namespace

TEST_CASE("every example problem parses, is named after its file and has ground truth",
          "[problem]") {
  int count = 0;
  for (const auto& entry : fs::directory_iterator(problemsDir())) {
    if (entry.path().extension() != ".toml") continue;
    ++count;
    INFO(entry.path().string());
    Problem p;
    REQUIRE_NOTHROW(p = ndc::loadProblem(entry.path()));
    CHECK(p.name == entry.path().stem().string());
    CHECK(p.path == entry.path().string());
    CHECK(p.n() >= 2);
    CHECK(p.k() >= 1);
    CHECK(p.k() < p.n());
    // k >= 3 examples (issue 44) state their Betti numbers, k + 1 of them, with chi their
    // alternating sum.
    if (p.k() >= 3 && !p.application) {
      const auto betti = p.expect.lists.find("betti");
      REQUIRE(betti != p.expect.lists.end());
      CHECK(betti->second.size() == std::size_t(p.k() + 1));
      long chi = 0;
      for (std::size_t i = 0; i < betti->second.size(); ++i)
        chi += (i % 2 ? -1 : 1) * betti->second[i];
      CHECK(p.expect.eulerCharacteristic == chi);
    }
    CHECK(p.domain.dim() == p.n());
    for (int j = 0; j < p.n(); ++j) CHECK(p.domain.lo[j] < p.domain.hi[j]);
    for (const auto& e : p.equations) CHECK(e.dim() == p.n());
    CHECK(p.expect.components.has_value());
    // Plain examples are closed manifolds or domain-bounded ones of known topology. Application
    // examples (paper Sec. 3) carry what was verified for them: their curves may end on the
    // parameter box (silhouette arcs), so no Euler characteristic is implied.
    if (p.application) continue;
    CHECK(p.expect.eulerCharacteristic.has_value());
    // A closed curve has Euler characteristic 0 whatever its number of loops.
    if (p.k() == 1) CHECK(*p.expect.eulerCharacteristic == 0);
  }
  CHECK(count >= 10);
}

TEST_CASE("example problems: dimensions and degrees", "[problem]") {
  auto load = [](const std::string& name) { return ndc::loadProblem(problemsDir() / name); };

  const Problem circle = load("circle.toml");
  CHECK(circle.n() == 2);
  CHECK(circle.m() == 1);
  CHECK(circle.k() == 1);
  CHECK(circle.equations[0].degrees() == std::vector<int>{2, 2});

  const Problem torus = load("torus.toml");
  CHECK(torus.k() == 2);
  CHECK(torus.equations[0].text() == "(x^2+y^2+z^2+0.84)^2 - 4*(x^2+y^2)");
  CHECK(torus.equations[0].degrees() == std::vector<int>{4, 4, 4});
  CHECK(torus.domain.lo == std::vector<double>{-1.5, -1.5, -0.5});
  CHECK(torus.domain.hi == std::vector<double>{1.5, 1.5, 0.5});

  const Problem clifford = load("clifford-torus.toml");
  CHECK(clifford.n() == 4);
  CHECK(clifford.k() == 2);
  CHECK(clifford.equations[0].degrees() == std::vector<int>{2, 2, 0, 0});
  CHECK(clifford.equations[1].degrees() == std::vector<int>{0, 0, 2, 2});
  CHECK(*clifford.expect.eulerCharacteristic == 0);

  const Problem genus2 = load("genus2.toml");
  CHECK(genus2.equations[0].degrees() == std::vector<int>{8, 8, 2});
  CHECK(*genus2.expect.eulerCharacteristic == -2);
  CHECK(genus2.expect.other.at("genus") == 2);

  const Problem r8 = load("circle-r8.toml");
  CHECK(r8.n() == 8);
  CHECK(r8.m() == 7);
  CHECK(r8.k() == 1);
  CHECK(r8.equations[1].degrees() == std::vector<int>{1, 1, 1, 0, 1, 0, 0, 1});
}

TEST_CASE("domainAs converts the domain to each scalar", "[problem]") {
  const Problem p =
      ndc::parseProblem(problemText(R"(["x^2 + y - 1"])", "[[-1.25, 2], [0, 3]]"), "a.toml");
  const auto d = p.domainAs<double>();
  CHECK(d.lo == std::vector<double>{-1.25, 0});
  CHECK(d.hi == std::vector<double>{2, 3});
  ndc::test::PrecisionScope<ndc::Mpfr> precision(200);
  const auto m = p.domainAs<ndc::Mpfr>();
  REQUIRE(m.dim() == 2);
  CHECK(m.lo[0] == ndc::Mpfr(-1.25));
  CHECK(m.hi[1] == ndc::Mpfr(3));
}

TEST_CASE("a valid problem: optional keys and [expect]", "[problem]") {
  const Problem p = ndc::parseProblem(
      "name = \"a.b_c-1\"\ndescription = \"d\"\nvariables = [\"x\", \"y_2\", \"Z\"]\n"
      "domain = [[-1, 1.5], [0, 1], [-3e-1, 2]]\nequations = [\"x*y_2 - Z/2\", 'x - 1']\n"
      "[expect]\ncomponents = 3\neuler_characteristic = -4\ngenus = 3\n",
      "ok.toml");
  CHECK(p.name == "a.b_c-1");
  CHECK(p.description == "d");
  CHECK(p.variables == std::vector<std::string>{"x", "y_2", "Z"});
  CHECK(p.domain.lo == std::vector<double>{-1, 0, -0.3});
  CHECK(p.m() == 2);
  CHECK(p.k() == 1);
  CHECK(*p.expect.components == 3);
  CHECK(*p.expect.eulerCharacteristic == -4);
  CHECK(p.expect.other.size() == 1);
  CHECK(p.expect.other.at("genus") == 3);

  // Without [expect] nothing is expected.
  const Problem q = ndc::parseProblem(problemText(), "ok.toml");
  CHECK_FALSE(q.expect.components);
  CHECK_FALSE(q.expect.eulerCharacteristic);
  CHECK(q.expect.other.empty());
}

TEST_CASE("InputError::at formats file, line and column", "[problem]") {
  CHECK(std::string(InputError::at("f.toml", 3, 7, "bad").what()) == "f.toml:3:7: bad");
  CHECK(std::string(InputError::at("f.toml", 3, 0, "bad").what()) == "f.toml:3: bad");
  CHECK(std::string(InputError::at("f.toml", 0, 0, "bad").what()) == "f.toml: bad");
  CHECK(std::string(InputError::at("f.toml", 0, 0, "two\nlines").what()) == "f.toml: two lines");
}

TEST_CASE("TOML syntax errors carry the position from toml++", "[problem]") {
  checkError("name = \"p\"\nvariables = [\"x\" \"y\"]\n", "bad.toml:2:", "TOML syntax error");
  checkError("name = \"p\"\nname = \"q\"\n", "bad.toml:2:", "TOML syntax error");
  checkError("name = \"unterminated\n", "bad.toml:1:", "TOML syntax error");
}

TEST_CASE("missing keys, unknown keys and wrong types", "[problem]") {
  checkError("", "bad.toml: ", "missing required key 'name'");
  checkError("name = \"p\"\n", "bad.toml: ", "problem 'p': missing required key 'variables'");
  checkError("name = \"p\"\nvariables = [\"x\", \"y\"]\n",
             "bad.toml: ", "missing required key 'domain'");
  checkError("name = \"p\"\nvariables = [\"x\", \"y\"]\ndomain = [[0, 1], [0, 1]]\n",
             "bad.toml: ", "missing required key 'equations'");

  checkError(problemText() + "foo = 1\n", "bad.toml:5:1:", "unknown key 'foo'");
  // An application problem has its own tables: plain keys are unknown there.
  checkError("application = \"bisector\"\n" + problemText(),
             "bad.toml:4:1:", "unknown key 'domain' in an application problem");
  checkError("name = \"p\"\napplication = \"smoothing\"\n",
             "bad.toml:2:", "unknown application 'smoothing'");

  checkError("name = 3\n", "bad.toml:1:8:", "name must be a string, not an integer");
  checkError(problemText(R"("x^2 + y^2 - 1")"),
             "bad.toml:4:13:", "equations must be an array, not a string");
  checkError(problemText(R"([1])"), "bad.toml:4:14:", "equation 1 must be a string");
  checkError(problemText(R"(["x - y"])", "[[-2, 2], [-2, 2]]", "[\"x\", 2]"),
             "bad.toml:2:", "variables[1] must be a string, not an integer");
  checkError(problemText() + "expect = 3\n", "bad.toml:5:", "expect must be a table");
  checkError(problemText() + "[expect]\ncomponents = 1.5\n",
             "bad.toml:6:", "expect.components must be an integer, not a float");
  checkError(problemText() + "[expect]\nnote = \"x\"\n", "bad.toml:6:1:",
             "unknown key 'note' in expect (known: components, euler_characteristic, vertices");
  checkError(problemText() + "[expect]\ngenus = \"x\"\n",
             "bad.toml:6:", "expect.genus must be an integer");
}

TEST_CASE("names and variables", "[problem]") {
  checkError("name = \"Circle\"\n", "bad.toml:1:8:", "must match [a-z0-9._-]+");
  checkError("name = \"two words\"\n", "bad.toml:1:8:", "must match");
  checkError("name = \"\"\n", "bad.toml:1:8:", "must match");
  checkError(problemText(R"(["x"])", "[[0, 1]]", R"(["x"])"),
             "bad.toml:2:13:", "at least 2 variables, got 1");
  checkError(problemText(R"(["x"])", "[[0, 1], [0, 1]]", R"(["x", "x"])"),
             "bad.toml:2:19:", "variable 'x' is listed twice");
  checkError(problemText(R"(["x"])", "[[0, 1], [0, 1]]", R"(["x", "2y"])"),
             "bad.toml:2:19:", "variable '2y' is not an identifier");
  checkError(problemText(R"(["x"])", "[[0, 1], [0, 1]]", R"(["x", "a b"])"),
             "bad.toml:2:19:", "is not an identifier");
}

TEST_CASE("domains", "[problem]") {
  checkError(problemText(R"(["x"])", "[[0, 1]]"),
             "bad.toml:3:10:", "domain has 1 intervals but there are 2 variables");
  checkError(problemText(R"(["x"])", "[[0, 1], [0, 1], [0, 1]]"),
             "bad.toml:3:10:", "domain has 3 intervals");
  checkError(problemText(R"(["x"])", "[[0, 1], [0]]"),
             "bad.toml:3:19:", "domain of 'y' must be an array [lo, hi] of 2 numbers");
  checkError(problemText(R"(["x"])", "[[0, 1], 5]"), "bad.toml:3:19:", "of 2 numbers");
  checkError(problemText(R"(["x"])", "[[0, 1], [0, \"1\"]]"),
             "bad.toml:3:23:", "domain of 'y': hi must be a number, not a string");
  checkError(problemText(R"(["x"])", "[[0, 1], [1, 1]]"),
             "bad.toml:3:19:", "domain of 'y' is empty or inverted");
  checkError(problemText(R"(["x"])", "[[2, 1], [0, 1]]"),
             "bad.toml:3:11:", "domain of 'x' is empty or inverted");
  checkError(problemText(R"(["x"])", "[[nan, 1], [0, 1]]"),
             "bad.toml:3:12:", "domain of 'x': lo must be finite, not nan");
  checkError(problemText(R"(["x"])", "[[0, 1], [-inf, 1]]"), "bad.toml:3:20:", "must be finite");
  checkError(problemText(R"(["x"])", "[[0, +inf], [0, 1]]"), "bad.toml:3:15:", "must be finite");
}

TEST_CASE("equation counts", "[problem]") {
  checkError(problemText("[]"),
             "bad.toml:4:13:", "between 1 and n-1 = 1 equations for n = 2 variables, got 0");
  checkError(problemText(R"(["x", "y"])"), "bad.toml:4:13:", "got 2");
  checkError(problemText(R"(["x", "y", "z"])", "[[0, 1], [0, 1], [0, 1]]", R"(["x", "y", "z"])"),
             "bad.toml:4:13:", "n-1 = 2 equations for n = 3 variables, got 3");
}

TEST_CASE("expression errors map to the file position of the equation", "[problem]") {
  // Line 4 is `equations = ["...`: the opening quote is column 14, the text starts at 15.
  checkError(problemText(R"(["x^2 + q"])"), "bad.toml:4:21:", "equation 1");
  checkError(problemText(R"(["x^2 + q"])"), "bad.toml:4:21:", "problem 'p'");
  checkError(
      problemText(R"(["x + y - 1", "x*q"])", "[[0, 1], [0, 1], [0, 1]]", R"(["x", "y", "z"])"),
      "bad.toml:4:30:", "equation 2");
  // Literal strings and multi-line strings map too.
  checkError(problemText("['x^2 + q']"), "bad.toml:4:21:", "equation 1");
  checkError(problemText("[\"\"\"\nx^2 +\n  q\"\"\"]"), "bad.toml:6:3:", "equation 1");
  // Basic-string escapes shift the columns: "\u0078" is x.
  checkError(problemText(R"(["\u0078 + q"])"), "bad.toml:4:24:", "equation 1");

  // Every non-polynomial construct is rejected with the equation named.
  for (const std::string eq :
       {"sin(x) + y", "x^2.5 + y", "x^-1 + y", "x^(-1) + y", "1/x + y", "y/(x + 1)",
        "x^2 + y^2 - 1)", "x + + ", "x ** 2 + y", "x # y", "", "2 x + y"}) {
    INFO("equation: " << eq);
    checkError(problemText("[\"" + eq + "\"]"), "bad.toml:4:", "problem 'p': equation 1: ");
  }
  // Division by a constant is fine; a constant equation is not a manifold.
  CHECK(errorOf(problemText(R"(["x/2 + y/(1 + 1) - 0.5"])")).empty());
  checkError(problemText(R"(["3"])"), "bad.toml:4:14:", "equation 1 is constant");
}

TEST_CASE("loadProblem: unreadable files", "[problem]") {
  const fs::path dir = fs::temp_directory_path() / "ndc-test-problem";
  fs::create_directories(dir);
  const fs::path missing = dir / "missing.toml";
  fs::remove(missing);
  try {
    ndc::loadProblem(missing);
    FAIL("no error");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()) ==
          missing.string() + ": cannot read the problem file: No such file or directory");
  }
  try {
    ndc::loadProblem(dir);
    FAIL("no error");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()) ==
          dir.string() + ": cannot read the problem file: it is a directory");
  }
  // A file's own name is used in its messages.
  const fs::path bad = dir / "bad.toml";
  std::ofstream(bad) << "name = \"p\"\nfoo = 2\n";
  try {
    ndc::loadProblem(bad);
    FAIL("no error");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).rfind(bad.string() + ":2:1: unknown key 'foo'", 0) == 0);
  }
  fs::remove_all(dir);
}
