/// \file fuzz_common.hpp
/// What the libFuzzer harnesses in tests/fuzz/ share: the evaluators run on an expression that
/// parsed (plain value, gradient, interval, Bernstein form), and the problem-file entry with its
/// expected exceptions. A finding is whatever is not an expected exception: a crash, a sanitizer
/// report, another exception type (libFuzzer reports the abort of an uncaught one), a timeout or
/// memory past -rss_limit_mb. Run by scripts/fuzz.sh (docs/testing.md).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "applications/load.hpp"
#include "framework/numeric/bernstein.hpp"
#include "framework/numeric/interval.hpp"
#include "framework/numeric/scalar.hpp"
#include "framework/problem/application.hpp"
#include "framework/problem/expression.hpp"
#include "framework/problem/problem.hpp"

namespace ndc::fuzz {

/// Largest Bernstein form the harnesses build (coefficients, the product of degrees + 1). The
/// problem reader allows kMaxCoefficients = 1e6 at degree up to kMaxDegree = 1000, where one
/// form costs seconds by design (docs/input-limits.md); the fuzzer wants thousands of inputs a
/// second, so larger forms are left to the unit tests.
inline constexpr double kFuzzCoefficients = 4096;

/// Aborts (a libFuzzer finding) with a message when `ok` is false.
inline void require(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz: check failed: %s\n", what);
    std::abort();
  }
}

/// Whether the Bernstein form of `e` is small enough to build in the harness.
inline bool smallForm(const Expression& e) {
  double coefficients = 1;
  for (int d : e.degrees()) {
    if (d > kMaxDegree) return false;
    coefficients *= d + 1.0;
  }
  return coefficients <= kFuzzCoefficients;
}

/// Runs every evaluator of `e` on `box` (a point inside it, the box as intervals, the Bernstein
/// form on it). Results may be infinite or NaN on extreme input; only the evaluation itself is
/// under test, plus one property that holds for any input: the interval value on the box
/// encloses the interval value at a point of the box (inclusion isotonicity of outward-rounded
/// interval arithmetic).
inline void exercise(const Expression& e, const Box<double>& box) {
  const int n = e.dim();
  std::vector<double> point(n), gradient(n);
  std::vector<Interval<double>> whole, at, igradient(n);
  for (int j = 0; j < n; ++j) {
    point[j] = box.lo[j] + 0.375 * (box.hi[j] - box.lo[j]);
    whole.emplace_back(box.lo[j], box.hi[j]);
    at.emplace_back(point[j], point[j]);
  }
  const double value = e.evaluate<double>(std::span<const double>(point));
  const double withGradient =
      e.evaluate<double>(std::span<const double>(point), std::span<double>(gradient));
  require(value == withGradient || (std::isnan(value) && std::isnan(withGradient)),
          "the value with and without the gradient differ");
  const Interval<double> range = e.evaluate<double>(std::span<const Interval<double>>(whole));
  const Interval<double> local = e.evaluate<double>(std::span<const Interval<double>>(at));
  e.evaluate<double>(std::span<const Interval<double>>(whole),
                     std::span<Interval<double>>(igradient));
  if (std::isfinite(range.lower()) && std::isfinite(range.upper()) &&
      std::isfinite(local.lower()) && std::isfinite(local.upper()))
    require(range.lower() <= local.lower() && local.upper() <= range.upper(),
            "the interval value on the box does not enclose the value at a point of it");
  if (smallForm(e)) {
    const Bernstein<double> form = e.toBernstein(box);
    form.evaluate(std::span<const double>(point));
    form.coefficientRange();
    for (int j = 0; j < n; ++j) {
      if (form.degree(j) > 0) {
        Bernstein<double> left, right;
        form.halve(j, left, right);
        form.derivative(j);
      }
    }
  }
}

/// The problem-file entry on `data`: parses (problem or application file), then exercises each
/// equation on the domain and, for an application, its image map.
inline void problemInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  Problem p;
  try {
    p = parseProblem(text, "fuzz.toml");
  } catch (const InputError&) {
    return;
  } catch (const ExpressionError&) {
    return;
  }
  require(p.n() >= 1 && p.m() >= 1 && p.k() >= 1, "a problem with no manifold was accepted");
  require(p.domain.dim() == p.n(), "the domain and the variables differ in number");
  for (int j = 0; j < p.n(); ++j)
    require(p.domain.lo[j] < p.domain.hi[j] && std::isfinite(p.domain.width(j)),
            "an empty or infinite domain was accepted");
  // B-spline input is one polynomial per patch (Problem::roots), not on the whole domain.
  const std::vector<Box<double>> boxes =
      p.roots.empty() ? std::vector<Box<double>>{p.domain} : p.roots;
  for (const Box<double>& box : boxes)
    require(box.dim() == p.n(), "a patch box in another number of variables");
  for (const Expression& e : p.equations) {
    require(e.dim() == p.n(), "an equation in another number of variables");
    exercise(e, boxes.front());
    if (boxes.size() > 1) exercise(e, boxes.back());
  }
  if (p.application) {
    std::vector<double> centre(p.n());
    for (int j = 0; j < p.n(); ++j) {
      centre[j] = 0.5 * (p.domain.lo[j] + p.domain.hi[j]);
      p.application->parameter(j, centre[j]);
    }
    p.application->image(centre);
    if (p.application->secondImage) (*p.application->secondImage)(centre);
  }
}

}  // namespace ndc::fuzz
