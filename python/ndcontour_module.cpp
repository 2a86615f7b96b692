// The Python module `ndcontour` (docs/python.md): solve a problem given as a path, TOML text or a
// dict, and get the mesh as numpy arrays, the summary as a dict, and the outputs of `solve --out`.
// The settings are validated by the command line's own code, so a bad value raises
// ndcontour.InputError with the message the CLI prints.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <toml++/toml.h>

#include <cstdint>
#include <memory>
#include <new>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "framework/applications/load.hpp"
#include "framework/cli/solve_options.hpp"
#include "framework/core/errors.hpp"
#include "framework/core/expectation.hpp"
#include "framework/core/io.hpp"
#include "framework/core/result.hpp"
#include "framework/core/summary.hpp"
#include "framework/pipeline/pipeline.hpp"

namespace py = pybind11;

namespace {

/// A Python value of a problem dict as a TOML node (tables, arrays, strings, numbers, booleans).
toml::table tableOf(const py::dict& dict, const std::string& where);

void appendTo(toml::array& array, const py::handle& value, const std::string& where);

template <class Insert>
void convert(const py::handle& value, const std::string& where, Insert&& insert) {
  // bool before int: Python's bool is an int.
  if (py::isinstance<py::bool_>(value)) return insert(value.cast<bool>());
  if (py::isinstance<py::int_>(value)) return insert(value.cast<std::int64_t>());
  if (py::isinstance<py::float_>(value)) return insert(value.cast<double>());
  if (py::isinstance<py::str>(value)) return insert(value.cast<std::string>());
  if (py::isinstance<py::dict>(value)) return insert(tableOf(value.cast<py::dict>(), where));
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    toml::array array;
    for (const py::handle& item : value) appendTo(array, item, where + "[]");
    return insert(std::move(array));
  }
  throw ndc::InputError("<dict>: " + where + ": a " +
                        py::str(value.get_type().attr("__name__")).cast<std::string>() +
                        " is not a TOML value (use str, int, float, bool, list or dict)");
}

void appendTo(toml::array& array, const py::handle& value, const std::string& where) {
  convert(value, where, [&](auto&& v) { array.push_back(std::forward<decltype(v)>(v)); });
}

toml::table tableOf(const py::dict& dict, const std::string& where) {
  toml::table table;
  for (const auto& [key, value] : dict) {
    if (!py::isinstance<py::str>(key))
      throw ndc::InputError("<dict>: " + where + ": keys must be strings");
    const std::string name = key.cast<std::string>();
    const std::string path = where.empty() ? name : where + "." + name;
    convert(value, path, [&](auto&& v) { table.insert(name, std::forward<decltype(v)>(v)); });
  }
  return table;
}

/// The problem: a dict (a problem file's tables), TOML text (a str with a line break), or a
/// path (str or os.PathLike).
ndc::Problem problemOf(const py::object& problem) {
  if (py::isinstance<py::dict>(problem)) {
    std::ostringstream text;
    text << tableOf(problem.cast<py::dict>(), "");
    return ndc::parseProblem(text.str(), "<dict>");
  }
  if (py::isinstance<py::str>(problem)) {
    const std::string s = problem.cast<std::string>();
    if (s.find('\n') != std::string::npos) return ndc::parseProblem(s, "<string>");
    return ndc::loadProblem(s);
  }
  if (py::hasattr(problem, "__fspath__"))
    return ndc::loadProblem(py::module_::import("os").attr("fspath")(problem).cast<std::string>());
  throw ndc::InputError("problem: expected a path, TOML text or a dict, not a " +
                        py::str(problem.get_type().attr("__name__")).cast<std::string>());
}

/// One solve's result, as the Python object `ndcontour.Result`.
struct Result {
  std::shared_ptr<ndc::RunResult> run;

  py::array_t<double> vertices() const {
    const auto rows = static_cast<py::ssize_t>(run->vertices.size() / std::max(1, run->n));
    py::array_t<double> out({rows, static_cast<py::ssize_t>(run->n)});
    std::copy(run->vertices.begin(), run->vertices.end(), out.mutable_data());
    return out;
  }
  py::array_t<std::int64_t> simplices() const {
    const int width = run->k + 1;
    const auto rows = static_cast<py::ssize_t>(run->simplices.size() / width);
    py::array_t<std::int64_t> out({rows, static_cast<py::ssize_t>(width)});
    std::copy(run->simplices.begin(), run->simplices.end(), out.mutable_data());
    return out;
  }
  py::dict summary() const {
    return py::module_::import("json").attr("loads")(ndc::toJson(run->summary));
  }
  std::vector<std::string> write(const std::string& dir, bool ascii, bool cells, bool vtk,
                                 bool obj) const {
    ndc::OutputOptions output;
    output.format = ascii ? ndc::PlyFormat::ascii : ndc::PlyFormat::binary;
    output.cells = cells;
    output.vtk = vtk;
    output.obj = obj;
    std::vector<std::string> written;
    {
      py::gil_scoped_release release;
      written = ndc::writeOutputs(dir, *run, output);
    }
    for (std::string& file : written) file = (std::filesystem::path(dir) / file).string();
    return written;
  }
};

/// `threads`: 1..kMaxThreads, as `--threads` accepts (the CLI checks it while parsing).
int threadsOf(const py::handle& value) {
  const std::string text = py::str(value).cast<std::string>();
  if (!py::isinstance<py::int_>(value) || py::isinstance<py::bool_>(value) ||
      value.cast<long long>() < 1 || value.cast<long long>() > ndc::cli::kMaxThreads)
    throw ndc::UsageError("--threads: '" + text + "' is not an integer in 1.." +
                          std::to_string(ndc::cli::kMaxThreads));
  return value.cast<int>();
}

/// The CLI's settings and checks for the keyword arguments of solve().
ndc::cli::SolveOptions optionsOf(const py::kwargs& kwargs) {
  ndc::cli::SolveOptions o;
  ndc::Settings& s = o.settings;
  for (const auto& [key, value] : kwargs) {
    const std::string name = key.cast<std::string>();
    if (value.is_none()) continue;
    if (name == "depth")
      s.depth = value.cast<int>();
    else if (name == "max_depth")
      s.maxDepth = value.cast<int>();
    else if (name == "tolerance")
      o.tolerance = value.cast<double>();
    else if (name == "bounding")
      s.bounding = value.cast<std::string>();
    else if (name == "subdivision")
      s.subdivision = value.cast<std::string>();
    else if (name == "projection")
      s.projection = value.cast<std::string>();
    else if (name == "classification")
      s.classification = value.cast<std::string>();
    else if (name == "connection")
      s.connection = value.cast<std::string>();
    else if (name == "scalar")
      s.scalar = value.cast<std::string>();
    else if (name == "precision")
      o.precision = value.cast<unsigned>();
    else if (name == "jitter")
      s.jitter = value.cast<std::uint64_t>();
    else if (name == "max_memory")
      o.maxMemory = py::str(value).cast<std::string>();
    else if (name == "threads")
      s.threads = threadsOf(value);
    else
      throw ndc::UsageError("solve(): unknown keyword argument '" + name + "'");
  }
  ndc::cli::validateSolveOptions(o);
  return o;
}

Result solve(const py::object& problemArg, const py::kwargs& kwargs) {
  ndc::cli::SolveOptions options = optionsOf(kwargs);
  const ndc::Problem problem = problemOf(problemArg);
  ndc::cli::validateSolveOptions(options, problem);
  auto run = std::make_shared<ndc::RunResult>();
  {
    py::gil_scoped_release release;  // other Python threads run during the solve
    *run = ndc::runPipeline(problem, options.settings);
    run->summary.expect = ndc::checkExpectation(problem.expect, run->summary.mesh, run->k);
  }
  return Result{std::move(run)};
}

std::string oneLine(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

}  // namespace

PYBIND11_MODULE(ndcontour, m) {
  m.doc() =
      "ndcontour: the common zero set of n - k polynomial constraints in n variables as a "
      "polyline (k = 1) or a triangle mesh (k = 2), in any dimension n (docs/python.md).";
  m.attr("__version__") = NDC_VERSION;
  static py::exception<ndc::InputError> inputError(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ndc::UsageError& e) {
      // The CLI's spelling: a usage error names no file and is prefixed by the program.
      inputError(("ndcontour: " + oneLine(e.what())).c_str());
    } catch (const ndc::InputError& e) {
      inputError(oneLine(e.what()).c_str());
    } catch (const std::bad_alloc&) {
      PyErr_SetString(PyExc_MemoryError, "ndcontour: out of memory (use a smaller depth)");
    }
  });

  py::class_<Result>(m, "Result", "The result of one solve (the outputs of `ndcontour solve`).")
      .def_property_readonly(
          "n", [](const Result& r) { return r.run->n; },
          "Number of variables (the ambient dimension).")
      .def_property_readonly(
          "k", [](const Result& r) { return r.run->k; },
          "Dimension of the manifold: 1 (polyline) or 2 (triangles).")
      .def_property_readonly("vertices", &Result::vertices,
                             "Welded vertices, an (N, n) float64 array.")
      .def_property_readonly("simplices", &Result::simplices,
                             "Segments (k = 1) or triangles (k = 2): an (M, k + 1) int64 array "
                             "of vertex rows.")
      .def_property_readonly("summary", &Result::summary,
                             "The summary, the same dict as summary.json (docs/contracts.md).")
      .def("write", &Result::write, py::arg("dir"), py::kw_only(), py::arg("ascii") = false,
           py::arg("cells") = false, py::arg("vtk") = false, py::arg("obj") = false,
           "Writes the files of `ndcontour solve --out DIR` (binary PLY unless ascii; "
           "cells.csv with cells, mesh.vtu with vtk, mesh.obj with obj) and returns their "
           "paths.")
      .def("__repr__", [](const Result& r) {
        const auto& mesh = r.run->summary.mesh;
        return "<ndcontour.Result " + r.run->summary.problem + ": n = " + std::to_string(r.run->n) +
               ", k = " + std::to_string(r.run->k) + ", " + std::to_string(mesh.vertices) +
               " vertices, " + std::to_string(r.run->simplices.size() / (r.run->k + 1)) +
               " simplices, " +
               (r.run->summary.topology.certified ? "certified" : "not certified") + ">";
      });

  m.def("solve", &solve, py::arg("problem"),
        "solve(problem, *, depth=6, max_depth=None, tolerance=None, bounding='linearized', "
        "subdivision='binary', projection='newton', classification='paper', "
        "connection='crossing', scalar='double', precision=None, jitter=None, "
        "max_memory=None, threads=None)\n\n"
        "Solves a problem: a path (str or os.PathLike), TOML text (a str with a line break) or "
        "a dict of the problem file's tables. The keywords are `ndcontour solve`'s options; "
        "bad input raises ndcontour.InputError (a ValueError) with the CLI's message. The GIL "
        "is released while the pipeline runs.");
}
