// The extension `ndcontour._core` of the Python package `ndcontour` (docs/python.md; the typed
// front, `solve`'s signature and the progress bar are in experiments/python/ndcontour/__init__.py):
// solve a problem given as a path, TOML text or a dict, and get the mesh as numpy arrays, the
// summary as a dict, and the outputs of `solve --out`. The settings are validated by the command
// line's own code, so a bad value raises ndcontour.InputError with the message the CLI prints.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <toml++/toml.h>

#include <chrono>
#include <cstdint>
#include <exception>
#include <future>
#include <limits>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "applications/load.hpp"
#include "framework/io/io.hpp"
#include "framework/io/result.hpp"
#include "framework/io/vertex_rows.hpp"
#include "framework/problem/expectation.hpp"
#include "framework/problem/summary.hpp"
#include "framework/util/errors.hpp"
#include "framework/util/stop.hpp"
#include "pipeline/options.hpp"
#include "pipeline/pipeline.hpp"

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
  std::vector<std::string> variables;  ///< the problem's variable names

  /// Columns [first, first + 3) of mesh.ply's vertex rows (x y z, or x2 y2 z2), as (N, 3).
  py::array_t<double> imageColumns(std::size_t first) const {
    ndc::VertexRows rows(*run);
    py::array_t<double> out({static_cast<py::ssize_t>(rows.count()), py::ssize_t{3}});
    double* o = out.mutable_data();
    for (std::size_t v = 0; v < rows.count(); ++v) {
      const auto row = rows(v);
      std::copy(row.begin() + first, row.begin() + first + 3, o + 3 * v);
    }
    return out;
  }
  /// The point in R^3 a viewer shows: the application's image, else the first three
  /// coordinates (zero-padded for n = 2).
  py::array_t<double> image() const { return imageColumns(0); }
  /// The convex hull's second image (x2 y2 z2), or None.
  py::object image2() const {
    if (!run->application || !run->application->secondImage) return py::none();
    return imageColumns(3 + static_cast<std::size_t>(run->n));
  }

  py::array_t<double> vertices() const {
    const auto rows = static_cast<py::ssize_t>(run->vertices.size() / std::max(1, run->n));
    py::array_t<double> out({rows, static_cast<py::ssize_t>(run->n)});
    std::copy(run->vertices.begin(), run->vertices.end(), out.mutable_data());
    // B-spline variables: the knot parameters of mesh.ply's u columns, not span coordinates.
    if (run->application) {
      double* v = out.mutable_data();
      for (py::ssize_t r = 0; r < rows; ++r)
        for (int j = 0; j < run->n; ++j)
          v[r * run->n + j] = run->application->parameter(j, v[r * run->n + j]);
    }
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
  std::vector<std::string> write(const py::object& dirArg, bool ascii, bool cells, bool vtk,
                                 bool vtkLegacy, bool obj) const {
    // A str or any os.PathLike, as solve() takes.
    if (!py::isinstance<py::str>(dirArg) && !py::hasattr(dirArg, "__fspath__"))
      throw py::type_error("write(): dir must be a str or an os.PathLike, not " +
                           py::str(dirArg.get_type().attr("__name__")).cast<std::string>());
    const std::string dir = py::module_::import("os").attr("fspath")(dirArg).cast<std::string>();
    ndc::OutputOptions output;
    output.format = ascii ? ndc::PlyFormat::ascii : ndc::PlyFormat::binary;
    output.cells = cells;
    output.vtk = vtk;
    output.legacyVtk = vtkLegacy;
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

/// The Python type name of `value`.
std::string typeName(const py::handle& value) {
  return py::str(value.get_type().attr("__name__")).cast<std::string>();
}

/// `value` as an integer option: an int (not a bool, which Python counts as one); anything else
/// is a TypeError naming the option.
long long integerOption(const std::string& name, const py::handle& value) {
  if (!py::isinstance<py::int_>(value) || py::isinstance<py::bool_>(value))
    throw py::type_error("solve(): " + name + " must be an int, not " + typeName(value));
  try {
    return value.cast<long long>();
  } catch (const py::cast_error&) {
    throw ndc::UsageError("solve(): " + name + " = " + py::str(value).cast<std::string>() +
                          " is out of range");
  }
}

/// `value` as a real option: an int or a float (not a bool).
double realOption(const std::string& name, const py::handle& value) {
  if ((!py::isinstance<py::int_>(value) && !py::isinstance<py::float_>(value)) ||
      py::isinstance<py::bool_>(value))
    throw py::type_error("solve(): " + name + " must be a float, not " + typeName(value));
  return value.cast<double>();
}

/// `value` as a string option.
std::string stringOption(const std::string& name, const py::handle& value) {
  if (!py::isinstance<py::str>(value))
    throw py::type_error("solve(): " + name + " must be a str, not " + typeName(value));
  return value.cast<std::string>();
}

/// An integer option in [lo, hi], as the CLI spells the range error.
int boundedOption(const std::string& name, const py::handle& value, long long lo, long long hi) {
  const long long v = integerOption(name, value);
  if (v < lo || v > hi)
    throw ndc::UsageError("solve(): " + name + " = " + std::to_string(v) + " is not in " +
                          std::to_string(lo) + ".." + std::to_string(hi));
  return static_cast<int>(v);
}

/// `threads`: 1..kMaxThreads, as `--threads` accepts (the CLI checks it while parsing).
int threadsOf(const py::handle& value) {
  const long long v = integerOption("threads", value);
  if (v < 1 || v > ndc::kMaxThreads)
    throw ndc::UsageError("--threads: '" + std::to_string(v) + "' is not an integer in 1.." +
                          std::to_string(ndc::kMaxThreads));
  return static_cast<int>(v);
}

/// The options of solve() that are not the CLI's: `timeout` (seconds, raising TimeoutError).
struct PythonOptions {
  std::optional<double> timeout;
};

/// The CLI's settings and checks for the keyword arguments of solve(). A value of the wrong
/// Python type is a TypeError naming the option; a bad value of the right type an InputError
/// with the CLI's message.
ndc::SolveOptions optionsOf(const py::kwargs& kwargs, PythonOptions& python) {
  ndc::SolveOptions o;
  ndc::Settings& s = o.settings;
  constexpr long long kIntMax = std::numeric_limits<int>::max();
  for (const auto& [key, value] : kwargs) {
    const std::string name = key.cast<std::string>();
    if (value.is_none()) continue;
    if (name == "depth")
      s.depth = boundedOption(name, value, std::numeric_limits<int>::min(), kIntMax);
    else if (name == "max_depth")
      s.maxDepth = boundedOption(name, value, std::numeric_limits<int>::min(), kIntMax);
    else if (name == "tolerance")
      o.tolerance = realOption(name, value);
    else if (name == "bounding")
      s.bounding = stringOption(name, value);
    else if (name == "subdivision")
      s.subdivision = stringOption(name, value);
    else if (name == "projection")
      s.projection = stringOption(name, value);
    else if (name == "classification")
      s.classification = stringOption(name, value);
    else if (name == "connection")
      s.connection = stringOption(name, value);
    else if (name == "scalar")
      s.scalar = stringOption(name, value);
    else if (name == "precision")
      o.precision = static_cast<unsigned>(boundedOption(name, value, 0, kIntMax));
    else if (name == "jitter") {
      const long long v = integerOption(name, value);
      if (v < 0) throw ndc::UsageError("solve(): jitter must be a non-negative int");
      s.jitter = static_cast<std::uint64_t>(v);
    } else if (name == "max_memory") {
      if (!py::isinstance<py::str>(value) &&
          (!py::isinstance<py::int_>(value) || py::isinstance<py::bool_>(value)))
        throw py::type_error("solve(): max_memory must be a str or an int, not " + typeName(value));
      o.maxMemory = py::str(value).cast<std::string>();
    } else if (name == "threads") {
      s.threads = threadsOf(value);
    } else if (name == "timeout") {
      python.timeout = realOption(name, value);
      if (!(*python.timeout > 0))
        throw ndc::UsageError("solve(): timeout must be a positive number of seconds");
    } else {
      throw py::type_error("solve() got an unexpected keyword argument '" + name + "'");
    }
  }
  ndc::validateSolveOptions(o);
  return o;
}

/// Only one solve runs at a time in the process: the stop request (stop.hpp) is process-wide.
std::mutex solveMutex;

/// Carries the pipeline's progress (called on its threads) to a Python callable called on the
/// caller's thread. Completed stages (fraction 1) are kept in order; a report of an unfinished
/// stage replaces the unfinished one before it, so a slow callable never holds the run back and
/// still sees every stage end.
class ProgressRelay {
 public:
  explicit ProgressRelay(py::object callable) : callable_(std::move(callable)) {}
  bool active() const { return !callable_.is_none(); }

  /// The pipeline's ndc::Progress (any thread).
  ndc::Progress sink() {
    if (!active()) return {};
    return [this](const char* stage, double fraction) {
      const std::lock_guard<std::mutex> lock(mutex_);
      // A stage ends once (the pipeline may report its end again).
      if (fraction >= 1.0 && last_ == stage) return;
      last_ = fraction >= 1.0 ? stage : "";
      if (!queue_.empty() && queue_.back().second < 1.0) queue_.pop_back();
      queue_.emplace_back(stage, fraction);
    };
  }
  /// Calls the Python callable with each queued report (the GIL held).
  void deliver() {
    if (!active()) return;
    std::vector<std::pair<std::string, double>> reports;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      reports.swap(queue_);
    }
    for (const auto& [stage, fraction] : reports) callable_(stage, fraction);
  }

 private:
  py::object callable_;
  std::mutex mutex_;
  std::vector<std::pair<std::string, double>> queue_;
  std::string last_;  ///< the stage whose end was the last report
};

/// Runs `work` on a worker thread while this thread, the caller's, waits with the GIL released
/// and takes it back every 50 ms to run Python's signal handlers and deliver the progress: an
/// exception either raises (KeyboardInterrupt on Ctrl-C, or one from the progress callable)
/// stops the run at its next work item and propagates from here.
template <class Work>
void runInterruptibly(Work&& work, ProgressRelay& progress) {
  std::exception_ptr failure;
  std::promise<void> done;
  std::future<void> finished = done.get_future();
  std::thread worker([&] {
    try {
      work();
    } catch (...) {
      failure = std::current_exception();
    }
    done.set_value();
  });
  std::exception_ptr interruption;
  for (bool ready = false; !ready;) {
    {
      py::gil_scoped_release release;  // other Python threads run during the solve
      ready = finished.wait_for(std::chrono::milliseconds(50)) == std::future_status::ready;
    }
    if (interruption) continue;
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      progress.deliver();
    } catch (...) {
      // Ctrl-C's handler or the callable raised: the worker ends at its next item.
      interruption = std::current_exception();
      ndc::requestStop(ndc::StopReason::kInterrupt);
    }
  }
  worker.join();
  if (interruption) std::rethrow_exception(interruption);
  if (failure) std::rethrow_exception(failure);
  progress.deliver();  // the last stage's end
}

/// Warns (Python's `warnings`) as the CLI does on standard error: ExpectationWarning for each
/// `[expect]` key the mesh does not match or that cannot be compared, UserWarning for an empty
/// zero set.
void warnAbout(const ndc::RunResult& run, const py::object& category) {
  if (ndc::emptyZeroSet(run.summary) &&
      PyErr_WarnEx(PyExc_UserWarning,
                   (run.summary.problem +
                    ": the zero set does not meet the domain (every cell is excluded by its "
                    "bounds): the mesh is empty")
                       .c_str(),
                   2) != 0)
    throw py::error_already_set();
  for (const ndc::ExpectCheck& check : run.summary.expect) {
    if (check.notComparable.empty() && check.ok) continue;
    const std::string line = run.summary.problem + ": " + ndc::describeCheck(check);
    // A filter may turn the warning into an exception ("error" action).
    if (PyErr_WarnEx(category.ptr(), line.c_str(), 2) != 0) throw py::error_already_set();
  }
}

py::object expectationWarning;

Result solve(const py::object& problemArg, const py::object& progressArg,
             const py::kwargs& kwargs) {
  if (!progressArg.is_none() && !PyCallable_Check(progressArg.ptr()))
    throw py::type_error("solve(): progress must be callable, True, False or None, not " +
                         typeName(progressArg));
  ProgressRelay progress(progressArg);
  PythonOptions python;
  ndc::SolveOptions options = optionsOf(kwargs, python);
  const ndc::Problem problem = problemOf(problemArg);
  ndc::validateSolveOptions(options, problem);
  auto run = std::make_shared<ndc::RunResult>();
  {
    py::gil_scoped_release release;
    const std::lock_guard<std::mutex> one(solveMutex);
    py::gil_scoped_acquire acquire;
    ndc::clearStop();
    if (python.timeout)
      ndc::setStopDeadline(std::chrono::steady_clock::now() +
                               std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                   std::chrono::duration<double>(*python.timeout)),
                           *python.timeout);
    try {
      runInterruptibly(
          [&] {
            *run = ndc::runPipeline(problem, options.settings, progress.sink());
            run->summary.expect = ndc::checkExpectation(problem.expect, run->summary.mesh, run->k);
          },
          progress);
    } catch (...) {
      ndc::clearStop();
      throw;
    }
    ndc::clearStop();
  }
  warnAbout(*run, expectationWarning);
  return Result{std::move(run), problem.variables};
}

/// For tests: a Result holding the given mesh, as a solve would (docs/python.md, "For tests"):
/// `vertices` (N, n) and `simplices` (M, k + 1) with 1 <= k < n; the summary holds n, k, the
/// name, the variables and the vertex count, and says the topology is not certified.
Result resultFromArrays(
    const py::array_t<double, py::array::c_style | py::array::forcecast>& v,
    const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>& s,
    const std::vector<std::string>& variables, const std::string& problem) {
  // The shapes: n columns of vertices, k + 1 of simplices, indices in range, names per column.
  if (v.ndim() != 2 || s.ndim() != 2 || v.shape(1) < 2 || s.shape(1) < 2 || s.shape(1) > v.shape(1))
    throw py::value_error(
        "_result_from_arrays: vertices (N, n) and simplices (M, k + 1), 1 <= k < n");
  if (!variables.empty() && static_cast<py::ssize_t>(variables.size()) != v.shape(1))
    throw py::value_error("_result_from_arrays: one variable name per column of vertices");
  auto run = std::make_shared<ndc::RunResult>();
  run->n = run->summary.n = static_cast<int>(v.shape(1));
  run->k = run->summary.k = static_cast<int>(s.shape(1)) - 1;
  run->summary.problem = problem;
  run->summary.variables = variables;
  run->summary.mesh.vertices = v.shape(0);
  run->summary.topology.reason = "a mesh given as arrays, not a solve";
  run->vertices.assign(v.data(), v.data() + v.size());
  for (py::ssize_t i = 0; i < s.size(); ++i) {
    if (s.data()[i] < 0 || s.data()[i] >= v.shape(0))
      throw py::value_error("_result_from_arrays: vertex index out of range");
    run->simplices.push_back(static_cast<std::int32_t>(s.data()[i]));
  }
  return Result{std::move(run), variables};
}

std::string oneLine(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
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
    } catch (const ndc::Stopped& e) {
      PyErr_SetString(PyExc_TimeoutError, ("ndcontour: " + std::string(e.what())).c_str());
    } catch (const std::bad_alloc&) {
      PyErr_SetString(PyExc_MemoryError, "ndcontour: out of memory (use a smaller depth)");
    }
  });

  expectationWarning = py::reinterpret_borrow<py::object>(
      PyErr_NewExceptionWithDoc("ndcontour.ExpectationWarning",
                                "A mesh that does not match the problem's [expect] (or a key "
                                "that cannot be compared): warned by solve(), as the CLI "
                                "prints it.",
                                PyExc_UserWarning, nullptr));
  m.attr("ExpectationWarning") = expectationWarning;

  py::class_<Result>(m, "Result", "The result of one solve (the outputs of `ndcontour solve`).")
      .def_property_readonly(
          "n", [](const Result& r) { return r.run->n; },
          "Number of variables (the ambient dimension).")
      .def_property_readonly(
          "k", [](const Result& r) { return r.run->k; },
          "Dimension of the manifold: 1 (polyline), 2 (triangles), 3 (tetrahedra), ...")
      .def_property_readonly("vertices", &Result::vertices,
                             "Welded vertices, an (N, n) float64 array.")
      .def_property_readonly("simplices", &Result::simplices,
                             "The k-simplices as an (M, k + 1) int64 array of vertex rows: "
                             "segments (k = 1), triangles (k = 2), tetrahedra (k = 3), ...")
      .def_property_readonly("image", &Result::image,
                             "The point in R^3 of each vertex, an (N, 3) float64 array: an "
                             "application's image (the bisector, the blend surface, ...), else "
                             "the first three coordinates (zero-padded for n = 2); mesh.ply's "
                             "x y z.")
      .def_property_readonly("image2", &Result::image2,
                             "The convex hull's second image (mesh.ply's x2 y2 z2) as an (N, 3) "
                             "array, or None.")
      .def_property_readonly(
          "variables", [](const Result& r) { return r.variables; },
          "The problem's variable names, one per column of `vertices`.")
      .def_property_readonly("summary", &Result::summary,
                             "The summary, the same dict as summary.json (docs/contracts.md).")
      .def("write", &Result::write, py::arg("dir"), py::kw_only(), py::arg("ascii") = false,
           py::arg("cells") = false, py::arg("vtk") = false, py::arg("vtk_legacy") = false,
           py::arg("obj") = false,
           "Writes the files of `ndcontour solve --out DIR` (binary PLY and VTU unless ascii; "
           "cells.csv with cells, mesh.vtu with vtk, mesh.vtk (legacy VTK, which meshio reads "
           "curves from) with vtk_legacy, mesh.obj with obj) and returns their paths. "
           "InputError for vtk or vtk_legacy with k >= 4 and obj with k >= 3 (no such cells).")
      .def("__repr__", [](const Result& r) {
        const auto& mesh = r.run->summary.mesh;
        return "<ndcontour.Result " + r.run->summary.problem + ": n = " + std::to_string(r.run->n) +
               ", k = " + std::to_string(r.run->k) + ", " + std::to_string(mesh.vertices) +
               " vertices, " + std::to_string(r.run->simplices.size() / (r.run->k + 1)) +
               " simplices, " +
               (r.run->summary.topology.certified ? "certified" : "not certified") + ">";
      });

  m.def("_result_from_arrays", &resultFromArrays, py::arg("vertices"), py::arg("simplices"),
        py::arg("variables") = std::vector<std::string>(), py::arg("problem") = "arrays",
        "For tests: a Result of the mesh given (vertices (N, n), simplices (M, k + 1)), whose "
        "write() writes the mesh files of a solve; its summary holds only n, k, the name, the "
        "variables and the vertex count (docs/python.md).");
  m.def("solve", &solve, py::arg("problem"), py::arg("progress"),
        "The pipeline behind ndcontour.solve (use that: it has the signature and the defaults). "
        "progress is None or a callable(stage: str, fraction: float).");
  m.def(
      "defaults",
      [] {
        const ndc::Settings s;
        py::dict d;
        d["depth"] = s.depth;
        d["bounding"] = s.bounding;
        d["subdivision"] = s.subdivision;
        d["projection"] = s.projection;
        d["classification"] = s.classification;
        d["connection"] = s.connection;
        d["scalar"] = s.scalar;
        return d;
      },
      "The defaults of `ndcontour solve`'s options (ndc::Settings), which solve()'s signature "
      "repeats (a test compares them).");
}
