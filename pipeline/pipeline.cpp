#include "pipeline/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <type_traits>
#include <variant>

#include "framework/mesh/analysis.hpp"
#include "framework/mesh/orientation.hpp"
#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/form_rounding.hpp"
#include "framework/numeric/grid.hpp"
#include "framework/numeric/parallel.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/application.hpp"
#include "framework/problem/budget.hpp"
#include "framework/problem/system.hpp"
#include "pipeline/rank.hpp"
#include "pipeline/singular.hpp"
#include "strategies/bounding/bounding.hpp"
#include "strategies/classification/classification.hpp"
#include "strategies/connection/connection.hpp"
#include "strategies/projection/projection.hpp"
#include "strategies/subdivision/subdivision.hpp"

namespace ndc {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// The grid of the run: the problem domain, shifted by a seeded sub-cell offset when
/// `--jitter` is given (so M avoids the lower-dimensional faces of the grid).
Grid makeGrid(const Problem& problem, const Settings& settings) {
  Grid grid;
  grid.n = problem.n();
  grid.depth = settings.depth;
  grid.domain = problem.domain;
  if (settings.jitter) {
    std::mt19937_64 rng(*settings.jitter);
    std::uniform_real_distribution<double> offset(0.05, 0.45);
    for (int j = 0; j < grid.n; ++j) {
      const double shift = offset(rng) * grid.cellWidth(j);
      grid.domain.lo[j] -= shift;
      grid.domain.hi[j] -= shift;
    }
  }
  return grid;
}

/// The most solution cells a k-manifold can plausibly meet at depth L in R^n: a k-manifold of
/// moderate size meets about c 2^(k L) cells of the final grid; the budget allows c up to
/// 2^(n + 6), capped at 2^27 (the memory guard's scale). More cells mean a zero set of a
/// higher dimension (x - x fills its domain: 2^(n L) cells).
std::int64_t cellBudget(const Problem& problem, int depth) {
  const int exponent = std::min(problem.k() * depth + problem.n() + 6, 27);
  return std::int64_t{1} << exponent;
}

/// What is left of a budget of `maxCells` solution cells once `used` are found (subdivide
/// reads 0 as no budget, so an exhausted budget is exceeded here).
std::int64_t remaining(std::int64_t maxCells, std::size_t used) {
  const std::int64_t left = maxCells - static_cast<std::int64_t>(used);
  if (left <= 0)
    throw CellBudgetExceeded("more than " + std::to_string(maxCells) + " solution cells");
  return left;
}

/// The message for more solution cells than a k-manifold can meet (cellBudget).
std::string notAManifold(const Problem& problem, const Settings& settings, std::int64_t cells) {
  return problem.path + ": more than " + std::to_string(cells) + " solution cells at depth " +
         std::to_string(settings.depth) +
         " (2^(k L + n + 6) with k = " + std::to_string(problem.k()) +
         ", L = " + std::to_string(settings.depth) + "): the zero set is not a " +
         std::to_string(problem.k()) +
         "-manifold (an equation that vanishes on a region, such as x - x, or equations that "
         "depend on each other)";
}

/// The memory budget of a run and what it allows (design of the estimate: docs/
/// input-limits.md, "Budgets").
struct MemoryPlan {
  double budget = 0;   ///< bytes the run may use
  double perCell = 0;  ///< bytes per solution cell (bytesPerSolutionCell)
  double base = 0;     ///< bytes whatever the size (baseRunBytes)
  bool byDefault = true;
  std::int64_t maxCells = 0;  ///< solution cells the budget holds

  /// Bytes for `cells` solution cells.
  double bytes(double cells) const { return base + cells * perCell; }

  /// The refusal of a run that needs `cells` solution cells: `prefix` ("more than ") and
  /// `suffix` (how the count is known) qualify the count.
  std::string overBudget(const Problem& problem, const Settings& settings, double cells,
                         const std::string& prefix = "", const std::string& suffix = "") const {
    char count[32];
    std::snprintf(count, sizeof count, cells < 1e7 ? "%.0f" : "%.3g", cells);
    return problem.path + ": depth " + std::to_string(settings.depth) + " needs " +
           (prefix.empty() ? "about " : prefix) + formatBytes(bytes(cells)) + " of memory (" +
           prefix + count + " solution cells" + suffix + "), over the budget of " +
           formatBytes(budget) +
           (byDefault ? " (" + std::to_string(std::lround(kDefaultMemoryShare * 100)) +
                            "% of this machine's memory)"
                      : "") +
           ": use a smaller depth, or --max-memory if the machine has more";
  }
};

/// A trial subdivision at depths coarser than the run's L (the memory and the time plans): the
/// solution cells counted at the last depth tried (`count(grid)`, memoised by the caller so the
/// two plans share their counts), extrapolated by 2^k per level. At coarse depths the ratio per
/// level is at most 2^k for a smooth M, so the extrapolation errs high. The trial stops at the
/// first depth with 2048 cells, or where `enough(estimate)`, or after a second of work, or at
/// depth L - 1. More cells than a k-manifold has at a trial depth are refused at once.
struct CellTrial {
  double estimate = 0;    ///< solution cells extrapolated to depth L (0: no depth tried)
  std::size_t found = 0;  ///< solution cells at `depth`
  int depth = 0;
  std::string how() const {
    return ", estimated from " + std::to_string(found) + " at depth " + std::to_string(depth);
  }
};

template <class Count, class Enough>
CellTrial trialCells(const Problem& problem, const Settings& settings, const Grid& grid,
                     const Count& count, const Enough& enough) {
  constexpr std::size_t kEnough = 2048;
  constexpr double kTrialSeconds = 1.0;
  const int L = settings.depth, k = problem.k();
  const auto start = Clock::now();
  CellTrial trial;
  for (int depth = std::max(1, problem.rootLevel); depth < L; ++depth) {
    Grid at = grid;
    at.depth = depth;
    try {
      trial.found = count(at);
    } catch (const CellBudgetExceeded&) {
      Settings coarse = settings;
      coarse.depth = depth;
      throw InputError(notAManifold(problem, coarse, cellBudget(problem, depth)));
    }
    trial.depth = depth;
    trial.estimate = static_cast<double>(trial.found) * std::ldexp(1.0, k * (L - depth));
    if (trial.found >= kEnough || enough(trial.estimate) || secondsSince(start) > kTrialSeconds)
      break;
  }
  return trial;
}

/// The memory plan of a run: its budget, and a refusal before any long work of a depth that
/// cannot fit. A k-manifold meets about c 2^(k L) cells of the depth-L grid, so where the
/// a-priori bound (cellBudget, and the 2^(n L) cells of the grid) does not fit the budget, a
/// trial subdivision at coarser depths (`count(grid)`: the solution cells there) measures c
/// and the count at depth L is extrapolated by 2^k per level. At coarse depths the ratio per
/// level is at most 2^k for a smooth M, so the extrapolation errs high; what it misses (a
/// feature too small for the trial) is refused after the real subdivision, which counts
/// exactly, and the address-space limit catches the rest. The trial stops at the first depth
/// with 2048 cells, or whose extrapolation fits the budget 64 times over.
template <class Count>
MemoryPlan planMemory(const Problem& problem, const Settings& settings, const Grid& grid,
                      const Count& count) {
  MemoryPlan plan;
  plan.byDefault = settings.maxMemoryBytes == 0;
  plan.budget =
      static_cast<double>(plan.byDefault ? defaultMemoryBudget() : settings.maxMemoryBytes);
  plan.perCell =
      bytesPerSolutionCell(problem.n(), problem.k(), settings.scalar, settings.precisionBits);
  plan.base = baseRunBytes(problem.n());
  if (plan.budget <= plan.base)
    throw InputError(problem.path + ": the memory budget of " + formatBytes(plan.budget) +
                     " is below the " + formatBytes(plan.base) + " any run of " +
                     std::to_string(problem.n()) + " variables needs (--max-memory)");
  const double cellsFit = std::floor((plan.budget - plan.base) / plan.perCell);
  plan.maxCells = static_cast<std::int64_t>(std::min(cellsFit, 9e18));

  const int L = settings.depth;
  const double crude = std::min(static_cast<double>(cellBudget(problem, L)),
                                std::ldexp(1.0, std::min(problem.n() * L, 1000)));
  if (plan.bytes(crude) <= plan.budget) return plan;
  // The trial; a run that clearly fits (kMargin times over) needs no finer count: the real
  // subdivision's cap still stops one the trial underestimates.
  constexpr double kMargin = 64;
  const CellTrial trial = trialCells(problem, settings, grid, count, [&](double estimate) {
    return plan.bytes(kMargin * estimate) <= plan.budget;
  });
  if (plan.bytes(trial.estimate) > plan.budget)
    throw InputError(plan.overBudget(problem, settings, trial.estimate, "", trial.how()));
  return plan;
}

/// The time model's verdict on `cells` solution cells (docs/input-limits.md, "Time estimate"):
/// records the estimate, refuses a run over kRefuseOverTimeout times `--timeout`, and announces
/// one over kAnnounceSeconds (once: `announced` is set). `how` says how the count is known.
void judgeTime(Summary& summary, const Problem& problem, const Settings& settings,
               const Notice& notice, double cells, const std::string& how, bool& announced) {
  const double work = workPerCell(problem);
  summary.estimatedSeconds = cells * work * kSecondsPerWork;
  std::ostringstream line;
  line.precision(2);
  line << problem.path << ": depth " << settings.depth << " is estimated to take about "
       << std::fixed << summary.estimatedSeconds << std::defaultfloat << " s (";
  if (cells < 1e9)
    line << std::llround(cells);
  else
    line << cells;
  line << " solution cells" << how << ", of " << work
       << " operations each: the equations' Bernstein forms)";
  if (settings.timeoutSeconds &&
      summary.estimatedSeconds > kRefuseOverTimeout * *settings.timeoutSeconds) {
    line << std::defaultfloat << std::setprecision(6) << ", over " << kRefuseOverTimeout
         << " times --timeout " << *settings.timeoutSeconds << " s: use a smaller depth";
    throw InputError(line.str());
  }
  if (summary.estimatedSeconds > kAnnounceSeconds && notice && !announced) {
    notice(line.str() + "; --timeout bounds it");
    announced = true;
  }
}

/// The time plan before the subdivision, which itself costs its boxes times the work per cell:
/// where the a-priori bound on the solution cells (cellBudget) would take over kAnnounceSeconds,
/// the trial's estimate; nullopt when no trial is needed.
template <class Count>
std::optional<CellTrial> planTime(const Problem& problem, const Settings& settings,
                                  const Grid& grid, const Count& count) {
  const double crude = static_cast<double>(cellBudget(problem, settings.depth));
  if (crude * workPerCell(problem) * kSecondsPerWork <= kAnnounceSeconds) return std::nullopt;
  return trialCells(problem, settings, grid, count, [](double) { return false; });
}

/// ZeroSetSubdiv over the B-spline patches of a problem (Problem::roots): each patch is
/// subdivided on its own, with its own Bernstein forms, down to the cells of the common grid, so
/// the solution cells (and everything built from them) form one grid across patch boundaries.
template <class S>
SolutionCells subdividePatches(const Problem& problem, const Settings& settings,
                               const Subdivision& subdivision, const Grid& grid,
                               const Progress& progress, std::int64_t maxCells) {
  const int n = grid.n, below = grid.depth - problem.rootLevel;
  SolutionCells cells;
  cells.grid = grid;
  std::vector<std::int32_t> global(n);
  const double roots = static_cast<double>(problem.roots.size());
  for (std::size_t r = 0; r < problem.roots.size(); ++r) {
    const Box<double>& root = problem.roots[r];
    Grid sub{n, below, root};
    const Bounding<S> bounding = createBounding<S>(settings.bounding, problem, toScalar<S>(root));
    Progress part;
    if (progress) part = [&](const char* stage, double f) { progress(stage, (r + f) / roots); };
    const SolutionCells found =
        subdivide<S>(bounding, subdivision, sub, part, remaining(maxCells, cells.size()));
    cells.visited += found.visited;
    // The patch's cell index at level J, then the cell's index inside it.
    for (std::size_t c = 0; c < found.size(); ++c) {
      const auto local = found.cell(c);
      for (int j = 0; j < n; ++j) {
        const double at = (root.lo[j] - grid.domain.lo[j]) / grid.domain.width(j);
        const auto patch =
            static_cast<std::int32_t>(std::llround(at * std::ldexp(1.0, problem.rootLevel)));
        global[j] = (patch << below) + local[j];
      }
      cells.add(global);
    }
  }
  return cells;
}

/// The largest error of a double Bernstein form of `e` on `box`, relative to the largest
/// coefficient, against the same form computed in 128-bit MPFR (from the exact decimal
/// literals): cancellation such as `(x + 1e16)^2 - 1e32 - 2e16*x` leaves nothing of x^2 in double.
double precisionLoss(const Expression& e, const Box<double>& box, const Bernstein<double>& form) {
  struct Restore {
    unsigned bits = mpfrPrecision();
    ~Restore() { setMpfrPrecision(bits); }
  } restore;
  setMpfrPrecision(128);
  const Bernstein<Mpfr> exact = e.toBernstein<Mpfr>(toScalar<Mpfr>(box));
  double largest = 0, error = 0;
  for (std::size_t j = 0; j < exact.coefficients().size(); ++j) {
    const Mpfr& c = exact.coefficients()[j];
    largest = std::max(largest, std::abs(toDouble(c)));
    error = std::max(error, std::abs(toDouble(Mpfr(form.coefficients()[j]) - c)));
  }
  if (largest == 0) return error > 0 ? std::numeric_limits<double>::infinity() : 0;
  return error / largest;
}

/// What checkEquations learnt of the rounding of an equation's double Bernstein forms,
/// relative to the largest coefficient: the largest bound proven along the way (form_rounding.hpp)
/// where it was below kProvenRounding, and the largest error measured against 128-bit arithmetic
/// on the first kPrecisionBoxes boxes where it was not.
struct EquationRounding {
  double proven = 0;
  double measured = 0;
  bool allProven = true;
};

/// A proven rounding bound this small (8192 units of round-off) is used as it is: it adds at
/// most 8 times the certificate's own margin of 1024 units to the crossing's margins, and
/// cancellation (a measured loss near the refusal at 1e-6) is far above it. Larger bounds are
/// measured instead.
constexpr double kProvenRounding = 0x1p-40;
constexpr std::size_t kPrecisionBoxes = 8;

/// Refuses an equation whose double Bernstein form on a box loses its precision (the error
/// against 128-bit arithmetic above 1e-6 of the largest coefficient); records its rounding.
void checkPrecision(const Problem& problem, std::size_t i, std::size_t b, const Box<double>& box,
                    const Bernstein<double>& form, double bound, EquationRounding& r) {
  constexpr double kMaxPrecisionLoss = 1e-6;
  const double proven = FormRounding::relative(form, bound);
  if (proven <= kProvenRounding) {
    r.proven = std::max(r.proven, proven);
    return;
  }
  r.allProven = false;
  const double loss = b < kPrecisionBoxes ? precisionLoss(problem.equations[i], box, form) : 0.0;
  r.measured = std::max(r.measured, loss);
  if (loss > kMaxPrecisionLoss) {
    std::ostringstream o;
    o << problem.path << ": equation " << i + 1 << " loses its precision in double "
      << "arithmetic (its Bernstein coefficients are off by " << loss
      << " of the largest, against 128-bit arithmetic): use --scalar mpfr, or expand and "
      << "simplify it";
    throw InputError(o.str());
  }
}

/// checkEquations for an equation without a dense form (densityFree, beyond kMaxCoefficients):
/// refuses it when its interval value on the domain is not finite, or when it vanishes at
/// three points spread over the domain with its gradient (a nonzero polynomial of degree 2
/// does not, but for an equation that is zero everywhere, `x0 - x0`).
template <class S>
void checkWithoutForm(const Problem& problem, std::size_t i, const Box<S>& domain) {
  const Expression& e = problem.equations[i];
  const std::size_t n = domain.lo.size();
  std::vector<Interval<double>> box;
  for (std::size_t j = 0; j < n; ++j)
    box.emplace_back(toDouble(domain.lo[j]), toDouble(domain.hi[j]));
  const Interval<double> range = e.evaluate<double>(std::span<const Interval<double>>(box));
  if (!std::isfinite(range.lower()) || !std::isfinite(range.upper()))
    throw InputError(problem.path + ": equation " + std::to_string(i + 1) +
                     " overflows on the domain (its value is beyond the range of double): "
                     "rescale the input");
  bool zero = true;
  std::vector<double> x(n), gradient(n);
  for (int p = 1; p <= 3 && zero; ++p) {
    // Points of a Weyl sequence: no two share a coordinate, none lies on a grid plane.
    for (std::size_t j = 0; j < n; ++j) {
      const double t = std::fmod(p * (0.6180339887498949 + 0.4142135623730951 * double(j)), 1.0);
      x[j] = box[j].lower() + t * (box[j].upper() - box[j].lower());
    }
    zero = e.evaluate<double>(std::span<const double>(x), std::span<double>(gradient)) == 0 &&
           std::all_of(gradient.begin(), gradient.end(), [](double g) { return g == 0; });
  }
  if (zero)
    throw InputError(problem.path + ": equation " + std::to_string(i + 1) +
                     " vanishes everywhere on the domain: its zero set is a region, not a "
                     "hypersurface");
}

/// Refuses equations whose Bernstein form on the domain (or on a B-spline patch) is zero (the
/// equation vanishes there: its zero set fills the region, `x - x`), not finite in double, or,
/// in a double run, so large that subdividing it would overflow (1e308 * x^2 + ...) or so
/// inexact that its zero set is noise (checkPrecision).
template <class S>
std::vector<EquationRounding> checkEquations(const Problem& problem, const Box<S>& domain) {
  constexpr double kLimit = 1e300;
  std::vector<Box<S>> boxes;
  if (problem.roots.empty()) boxes.push_back(domain);
  for (const Box<double>& patch : problem.roots) boxes.push_back(toScalar<S>(patch));
  std::vector<EquationRounding> rounding(problem.equations.size());
  for (std::size_t i = 0; i < problem.equations.size(); ++i) {
    if (denseCoefficients(problem.equations[i]) > kMaxCoefficients) {
      // No dense form to check (densityFree): by evaluation; no Bernstein path will use it.
      checkWithoutForm(problem, i, domain);
      continue;
    }
    for (std::size_t b = 0; b < boxes.size(); ++b) {
      const Box<S>& box = boxes[b];
      Bernstein<S> form;
      if constexpr (std::is_same_v<S, double>) {
        double bound = 0;
        form = problem.equations[i].toBernstein(box, bound);
        checkPrecision(problem, i, b, box, form, bound, rounding[i]);
      } else {
        form = problem.equations[i].template toBernstein<S>(box);
      }
      bool zero = true;
      for (const S& c : form.coefficients()) {
        using std::abs;
        zero = zero && c == S(0);
        // Residuals, outputs and the crossing's level are in double in every scalar.
        if (!std::isfinite(toDouble(c)))
          throw InputError(problem.path + ": equation " + std::to_string(i + 1) +
                           " overflows on the domain (a Bernstein coefficient is beyond the "
                           "range of double): rescale the input");
        if (std::is_same_v<S, double> && !(abs(c) <= S(kLimit))) {
          std::ostringstream o;
          o << problem.path << ": equation " << i + 1 << " reaches " << toDouble(c)
            << " on the domain (its Bernstein coefficients must stay below " << kLimit
            << " in magnitude for double arithmetic): rescale it, or use --scalar mpfr";
          throw InputError(o.str());
        }
      }
      if (zero)
        throw InputError(problem.path + ": equation " + std::to_string(i + 1) +
                         " vanishes everywhere on " +
                         (problem.roots.empty() ? "the domain" : "a B-spline patch") +
                         ": its zero set is a region, not a hypersurface");
    }
  }
  return rounding;
}

/// The rounding bound of each equation's Bernstein coefficients (relative to the largest) that
/// the certificate assumes: the proven bound where every box had one; otherwise also the
/// measured loss against 128-bit arithmetic with a factor of 4 for the boxes not measured
/// (B-spline patches beyond the first 8). In MPFR the conversion is exact to far below what
/// any certificate resolves (all zero).
std::vector<double> coefficientErrors(const std::vector<EquationRounding>& rounding) {
  std::vector<double> out;
  for (const EquationRounding& r : rounding)
    out.push_back(r.allProven ? r.proven : std::max(r.proven, 4 * r.measured));
  return out;
}

/// The children of a cell that the run's bounding cannot exclude (adaptive refinement): the
/// subdivision of the cell's box by one level, n entries (0 or 1, the half of each axis) per
/// child (ConnectionInput::refine). The subdivision searches for them (binary subdivision:
/// about n boxes per kept child), never through all 2^n.
template <class S>
std::vector<std::uint8_t> refineCell(const Problem& problem, const Settings& settings,
                                     const Subdivision& subdivision, const Box<double>& cell) {
  const int n = problem.n();
  const Bounding<S> bounding = createBounding<S>(settings.bounding, problem, toScalar<S>(cell));
  const SolutionCells children = subdivide<S>(bounding, subdivision, Grid{n, 1, cell});
  std::vector<std::uint8_t> halves;
  halves.reserve(children.size() * std::size_t(n));
  for (std::size_t c = 0; c < children.size(); ++c) {
    const auto index = children.cell(c);
    for (int j = 0; j < n; ++j) halves.push_back(static_cast<std::uint8_t>(index[j] & 1));
  }
  return halves;
}

}  // namespace

/// A certified run must give a manifold mesh; the welded mesh is checked once more, so that a
/// flaw between the certificate and the output (welding, joining at singular points) can
/// never reach the user as a certified wrong answer.
void checkCertificate(Summary& summary) {
  TopologyRecord& t = summary.topology;
  if (!t.certified) return;
  const MeshStats& m = summary.mesh;
  std::string flaw;
  if (m.nonmanifoldEdges > 0) flaw = "non-manifold edges";
  if (m.nonmanifoldFacets > 0) flaw = "non-manifold facets";
  if (summary.k == 1 && m.branchVertices > 0) flaw = "branch vertices";
  if (!summary.singularPoints.empty()) flaw = "singular points";
  if (flaw.empty()) return;
  t.certified = false;
  t.reason = "the certificate holds but the welded mesh has " + flaw;
}

/// The summary's header: the problem, and the settings with each strategy by name and its
/// parameter values apart (contracts 4.3).
void describeRun(Summary& summary, const Problem& problem, const Settings& settings,
                 const StrategyChoices& choices, unsigned precisionBits) {
  summary.problem = problem.name;
  summary.n = problem.n();
  summary.k = problem.k();
  summary.variables = problem.variables;
  summary.settings = settings;
  summary.settings.precisionBits = precisionBits;
  summary.settings.threads = effectiveThreads(settings.threads);
  summary.settings.bounding = choices.bounding.name;
  summary.settings.subdivision = choices.subdivision.name;
  summary.settings.projection = choices.projection.name;
  summary.settings.classification = choices.classification.name;
  summary.settings.connection = choices.connection.name;
  summary.parameters = {{"bounding", choices.bounding.parameters.json()},
                        {"subdivision", choices.subdivision.parameters.json()},
                        {"projection", choices.projection.parameters.json()},
                        {"classification", choices.classification.parameters.json()},
                        {"connection", choices.connection.parameters.json()}};
}

namespace {

/// B-spline input keeps its knots on grid planes: no jitter, and a depth at which every knot
/// span is a grid cell.
void checkPiecewiseSettings(const Problem& problem, const Settings& settings) {
  if (!problem.roots.empty() && settings.jitter)
    throw InputError(
        problem.path +
        ": --jitter cannot be used with B-spline input: the knots must stay on grid planes");
  if (settings.depth < problem.rootLevel)
    throw InputError("depth " + std::to_string(settings.depth) + " is below " +
                     std::to_string(problem.rootLevel) +
                     ", the level at which every B-spline knot span is a grid cell");
}

/// The connection's record of the topology; a connection that does not certify says so.
template <class S>
void recordTopology(Summary& summary, const ConnectionOutput<S>& connected,
                    const ModelSpec& connection, int depth) {
  summary.topology = connected.topology;
  if (!connection.capabilities.certifies) {
    const std::string certifying =
        connectionsThat([](const Capabilities& c) { return c.certifies; });
    summary.topology.certified = false;  // whatever the model's record says
    summary.topology.baseLevel = summary.topology.maxLevel = depth;
    summary.topology.maxDepth = depth;
    summary.topology.reason = "the " + connection.name + " connection does not certify topology (" +
                              certifying +
                              (certifying.find(',') == std::string::npos ? " does)" : " do)");
  }
  summary.ambiguousCells = connected.ambiguousCells;
  summary.singularCells = connected.singularCells;
  summary.offManifoldVertices = connected.offManifoldVertices;
  summary.perturbation = connected.perturbation;
}

/// Alg. 1 (1): ZeroSetSubdiv at the final depth within the memory budget and the cell budget
/// of a k-manifold (bounding: one over the domain, or none for one per B-spline patch).
template <class S>
SolutionCells solutionCells(Summary& summary, const Problem& problem, const Settings& settings,
                            const Grid& grid, const std::optional<Bounding<S>>& bounding,
                            const Subdivision& subdivision, const Progress& progress,
                            const Notice& notice) {
  // ZeroSetSubdiv at a depth, with a budget of solution cells.
  const auto subdivideAt = [&](const Grid& at, std::int64_t maxCells, const Progress& report) {
    return bounding ? subdivide<S>(*bounding, subdivision, at, report, maxCells)
                    : subdividePatches<S>(problem, settings, subdivision, at, report, maxCells);
  };
  // The plans' trials count each coarse depth once.
  std::map<int, std::size_t> counted;
  const auto countAt = [&](const Grid& at) {
    if (const auto it = counted.find(at.depth); it != counted.end()) return it->second;
    return counted[at.depth] = subdivideAt(at, cellBudget(problem, at.depth), Progress{}).size();
  };
  const MemoryPlan plan = planMemory(problem, settings, grid, countAt);
  summary.memoryBudget = plan.budget;
  // A run whose cells are dear (high degree) is judged before its subdivision too.
  bool announced = false;
  if (const auto trial = planTime(problem, settings, grid, countAt); trial && trial->depth > 0)
    judgeTime(summary, problem, settings, notice, trial->estimate, trial->how(), announced);

  // The solution cells of the final depth.
  auto t = Clock::now();
  const std::int64_t maxCells = std::min(cellBudget(problem, settings.depth), plan.maxCells);
  const SolutionCells cells = [&] {
    try {
      return subdivideAt(grid, maxCells, progress);
    } catch (const CellBudgetExceeded&) {
      throw InputError(maxCells < cellBudget(problem, settings.depth)
                           ? plan.overBudget(problem, settings, maxCells + 1, "more than ")
                           : notAManifold(problem, settings, maxCells));
    }
  }();
  // Now the count is known: refuse before the memory-hungry stages what cannot fit.
  summary.estimatedMemory = plan.bytes(static_cast<std::int64_t>(cells.size()));
  if (summary.estimatedMemory > plan.budget)
    throw InputError(plan.overBudget(problem, settings, static_cast<std::int64_t>(cells.size())));
  summary.tSubdivision = secondsSince(t);
  summary.visited = cells.visited;
  summary.solution = static_cast<std::int64_t>(cells.size());
  // The exact count: the estimate the other stages are judged by.
  judgeTime(summary, problem, settings, notice, static_cast<double>(cells.size()), "", announced);
  return cells;
}

/// Counts the normal, abnormal and failed cells.
void countClasses(Summary& summary, const std::vector<CellClass>& classes) {
  for (CellClass c : classes) {
    if (c == CellClass::kNormal) ++summary.normal;
    if (c == CellClass::kAbnormal) ++summary.abnormal;
    if (c == CellClass::kFailed) ++summary.failed;
  }
}

/// The complex joined at the singular points of M (pipeline/singular.hpp), then
/// welded (vertices closer than 1e-9 of the domain's largest width are one), with no vertex
/// that belongs to no simplex.
template <class S>
Complex<S> weldAtSingularPoints(Complex<S>& complex, const std::vector<SingularPoint>& points,
                                const Grid& grid) {
  double diameter = 0;
  for (int j = 0; j < grid.n; ++j) diameter = std::max(diameter, grid.domain.width(j));
  joinAtSingularPoints<S>(complex, points, grid);
  // For k >= 3 the crossing connection makes each vertex once, one per piece of M in a cell:
  // two cells' vertices may still land on one point of M (a grid vertex on a symmetric M), and
  // welding them would pinch the complex (docs/crossing.md, "Any k").
  if (complex.k >= 3 && points.empty()) {
    dropUnusedVertices(complex);
    return complex;
  }
  Complex<S> welded = weld<S>(complex, 1e-9 * diameter);
  dropUnusedVertices(welded);
  return welded;
}

/// The outputs in double: the welded mesh (its simplices oriented by the caller) and the
/// per-cell data.
template <class S>
void writeBack(RunResult& result, const Complex<S>& welded, const SolutionCells& cells,
               const Grid& grid, const Box<S>& domain, const Projections<S>& projections,
               const std::vector<CellClass>& classes) {
  const auto n = static_cast<std::size_t>(grid.n);
  result.vertices.reserve(welded.vertices.size());
  for (const S& v : welded.vertices) result.vertices.push_back(toDouble(v));
  result.cellIndex = cells.index;
  result.cellClass = classes;
  // Each cell writes its own slots.
  result.cellCentre.resize(cells.size() * n);
  result.cellPoint.resize(cells.size() * n);
  parallelFor(
      cells.size(),
      [&](std::size_t c) {
        const Box<S> box = cellBox(grid, domain, cells.cell(c));
        for (std::size_t j = 0; j < n; ++j) {
          result.cellCentre[c * n + j] = toDouble(S((box.lo[j] + box.hi[j]) / 2));
          result.cellPoint[c * n + j] = toDouble(projections.at(c)[j]);
        }
      },
      1024);
}

/// Application problems: the image map and where its denominator vanishes on the mesh, and the
/// singular points and uncertified boxes in the documented knot parameters.
void applicationOutputs(RunResult& result, const Problem& problem) {
  if (!problem.application) return;
  Summary& summary = result.summary;
  result.application = problem.application;
  summary.application = problem.application->name;
  summary.singularName = problem.application->singularName;
  const std::size_t count = result.vertices.size() / static_cast<std::size_t>(problem.n());
  for (std::size_t v = 0; v < count; ++v) {
    bool singular = false;
    problem.application->image(
        std::span<const double>(result.vertices.data() + v * problem.n(), problem.n()), &singular);
    summary.imageSingularVertices += singular;
  }
  // B-spline variables are solved in span coordinates; the outputs speak the documented knot
  // parameters, as mesh.ply's u columns do: the singular points and the uncertified boxes
  // (the map is increasing, so a box stays a box). The vertices stay in span coordinates in
  // the result and are mapped where they are written (vertex_rows.hpp, the Python module).
  const ApplicationData& app = *problem.application;
  for (SingularPoint& p : summary.singularPoints)
    for (std::size_t j = 0; j < p.point.size(); ++j)
      p.point[j] = app.parameter(static_cast<int>(j), p.point[j]);
  for (UncertifiedCell& c : summary.topology.uncertified)
    for (std::size_t j = 0; j < c.lo.size(); ++j) {
      c.lo[j] = app.parameter(static_cast<int>(j), c.lo[j]);
      c.hi[j] = app.parameter(static_cast<int>(j), c.hi[j]);
    }
}

template <class S>
RunResult run(const Problem& problem, const Settings& settings, const StrategyChoices& choices,
              const Progress& progress, const Notice& notice) {
  const auto start = Clock::now();
  RunResult result;
  result.n = problem.n();
  result.k = problem.k();
  Summary& summary = result.summary;
  describeRun(summary, problem, settings, choices, ScalarTraits<S>::precisionBits());

  // Choose every strategy before any work, so a bad spec costs nothing.
  const Grid grid = makeGrid(problem, settings);
  const Box<S> domain = toScalar<S>(grid.domain);
  const System<S> system(problem);
  const std::vector<EquationRounding> rounding = checkEquations<S>(problem, domain);
  checkPiecewiseSettings(problem, settings);
  // One bounding over the domain, or one per B-spline patch (built in subdividePatches).
  const std::optional<Bounding<S>> bounding =
      problem.roots.empty()
          ? std::optional<Bounding<S>>(createBounding<S>(choices.bounding, problem, domain))
          : std::nullopt;
  const Subdivision subdivision = createSubdivision(choices.subdivision);
  const Projection<S> projection = createProjection<S>(choices.projection, system);
  const Classification classification = createClassification(choices.classification);
  const Connection connection = createConnection(choices.connection);
  const SolutionCells cells =
      solutionCells<S>(summary, problem, settings, grid, bounding, subdivision, progress, notice);

  // Alg. 1: project each cell's centroid onto M, then classify the cell.
  auto t = Clock::now();
  const Projections<S> projections = projectCells<S>(projection, cells, domain, progress);
  // Dependent equations make M thicker than k: say so now, before the connection's work.
  checkRankOnM<S>(problem, system, projections);
  const std::vector<CellClass> classes =
      classifyCells<S>(classification, cells, domain, projections);
  summary.tProjection = secondsSince(t);
  countClasses(summary, classes);

  // Alg. 1: connect the cells into a complex.
  const Projector<S> project = makeProjector<S>(projection);
  t = Clock::now();
  ConnectionInput<S> input{problem, system, cells, projections, classes, project, problem.k()};
  input.maxLevel = maxDepthOf(problem, settings);
  input.tolerance = settings.tolerance;
  input.refineSeconds = settings.timeoutSeconds
                            ? std::min(kRefineSeconds, *settings.timeoutSeconds / 4)
                            : kRefineSeconds;
  input.refine = [&](const Box<double>& cell) {
    return refineCell<S>(problem, settings, subdivision, cell);
  };
  input.coefficientError = coefficientErrors(rounding);
  input.progress = progress;
  if (progress) progress("connection", 0);
  ConnectionOutput<S> connected = connect<S>(connection, input);
  if (progress) progress("connection", 1);
  summary.tConnection = secondsSince(t);
  recordTopology<S>(summary, connected, connectionRegistry().find(choices.connection.name).spec,
                    settings.depth);

  // Analysis on the welded mesh.
  t = Clock::now();
  if (progress) progress("analysis", 0);
  summary.singularPoints =
      findSingularPoints<S>(problem, system, projection, cells, projections, domain).points;
  if (progress) progress("analysis", 0.25);
  const Complex<S> welded =
      weldAtSingularPoints<S>(connected.complex, summary.singularPoints, grid);
  // The orientation of the output's simplices beside the analysis, which reads neither them
  // nor the flag (a sequential search that would otherwise follow the parallel analysis).
  result.simplices = welded.simplices;
  bool orientable = true;
  TaskBeside orientation;
  orientation.start(
      [&result, &orientable] { orientable = orientSimplices(result.k, result.simplices); });
  summary.mesh = analyse<S>(welded, system, project);
  orientation.wait();
  summary.mesh.orientable = orientable;
  summary.tAnalysis = secondsSince(t);
  if (progress) progress("analysis", 1);
  checkCertificate(summary);

  writeBack<S>(result, welded, cells, grid, domain, projections, classes);
  applicationOutputs(result, problem);
  summary.tTotal = secondsSince(start);
  return result;
}

}  // namespace

int defaultMaxDepth(int n, int depth) {
  int level = depth + kDefaultRefinementLevels;
  while (level > depth && !Grid::fits(n, level)) --level;
  return level;
}

int maxDepthOf(const Problem& problem, const Settings& settings) {
  return settings.maxDepth == 0 ? defaultMaxDepth(problem.n(), settings.depth) : settings.maxDepth;
}

void checkDepths(int depth, int maxDepth, int n, std::string_view file) {
  const std::string at = file.empty() ? std::string() : std::string(file) + ": ";
  const auto check = [&](const char* option, int level) {
    const std::string given = at + option + " " + std::to_string(level);
    if (level < kMinDepth || level > kMaxDepth)
      throw UsageError(given + " is out of range (accepted: " + std::to_string(kMinDepth) + ".." +
                       std::to_string(kMaxDepth) + ")");
    // Cells are keyed by a packed 128-bit multi-index of n * level bits (grid.hpp).
    if (n > 0 && !Grid::fits(n, level))
      throw UsageError(given + " is too deep for " + std::to_string(n) + " variables: n * level " +
                       "must be at most " + std::to_string(kCellKeyBits) + ", with at most " +
                       std::to_string(kMaxCellKeyAxes) + " variables (accepted: " + option +
                       " <= " + std::to_string(std::min(kMaxDepth, Grid::deepestFor(n))) + ")");
  };
  check("--depth", depth);
  if (maxDepth == 0) return;
  check("--max-depth", maxDepth);
  if (maxDepth < depth)
    throw UsageError(at + "--max-depth " + std::to_string(maxDepth) + " is below --depth " +
                     std::to_string(depth));
}

StrategyChoices parseStrategies(const Settings& settings) {
  return {boundingRegistry().parse(settings.bounding),
          subdivisionRegistry().parse(settings.subdivision),
          projectionRegistry().parse(settings.projection),
          classificationRegistry().parse(settings.classification),
          connectionRegistry().parse(settings.connection)};
}

RunResult runPipeline(const Problem& problem, const Settings& settings, const Progress& progress,
                      const Notice& notice) {
  checkDepths(settings.depth, settings.maxDepth, problem.n(), problem.path);
  // Every strategy spec is checked before any work (UsageError on a bad name or parameter).
  const StrategyChoices choices = parseStrategies(settings);
  // A connection builds the k its capabilities declare: refuse other k before any work.
  requireBuildsK(connectionRegistry().find(choices.connection.name).spec, problem.k(),
                 problem.path + ": ");
  // Cells must stay wider than the rounding of their coordinates (and than subnormal numbers),
  // or neighbouring grid planes coincide and cells collapse.
  const double eps = std::numeric_limits<double>::epsilon();
  for (int j = 0; j < problem.n(); ++j) {
    const double lo = problem.domain.lo[j], hi = problem.domain.hi[j];
    const double width = std::ldexp(hi - lo, -settings.depth);
    if (!(width > 64 * eps * std::max(std::abs(lo), std::abs(hi))) ||
        !(width > std::numeric_limits<double>::min() / eps)) {
      std::ostringstream o;
      o << problem.path << ": depth " << settings.depth << " is too deep for the domain [" << lo
        << ", " << hi << "] of '" << problem.variables[j] << "': its cells (width " << width
        << ") are below the rounding of their coordinates";
      throw InputError(o.str());
    }
  }
  if (settings.scalar != "double" && settings.scalar != "mpfr")
    throw InputError("unknown scalar '" + settings.scalar + "' (expected double or mpfr)");
  // Every parallel loop of the run uses the arena of --threads (framework/numeric/parallel.hpp).
  return withThreads(settings.threads, [&] {
    if (settings.scalar == "double")
      return run<double>(problem, settings, choices, progress, notice);
    // The run's precision applies to this run only: restore the caller's afterwards.
    struct Restore {
      unsigned bits = mpfrPrecision();
      ~Restore() { setMpfrPrecision(bits); }
    } restore;
    setMpfrPrecision(settings.precisionBits);
    return run<Mpfr>(problem, settings, choices, progress, notice);
  });
}

}  // namespace ndc
