/// \file applications.hpp
/// The five constraint systems of the paper's Sec. 3 as problem builders.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "applications/freeform.hpp"
#include "framework/problem/problem.hpp"
#include "framework/problem/toml_reader.hpp"

namespace ndc {

/// What an application problem file holds, read and validated by buildApplication before the
/// application's builder runs (which checks what its system needs: how many surfaces, a motion,
/// an eye point, alpha ranges).
struct ApplicationInput {
  const TomlReader* reader = nullptr;
  const toml::table* root = nullptr;
  std::string application;  ///< the `application` value
  std::string name, description;
  std::vector<SurfaceSpec> surfaces;           ///< `[[surfaces]]`, in file order
  std::optional<MotionSpec> motion;            ///< `[motion]`
  std::optional<std::array<double, 3>> eye;    ///< `eye = [x, y, z]`
  std::optional<std::array<double, 4>> alpha;  ///< `alpha = [[lo1, hi1], [lo2, hi2]]`
  Expectation expect;
  /// Fails (InputError at the `application` key) with `message`.
  [[noreturn]] void fail(const std::string& message) const;
};

/// Builds an application problem (`application = "NAME"`) from its parsed document
/// (ApplicationBuilder of framework/problem/toml_reader.hpp); throws InputError.
Problem buildApplication(const toml::table& root, TomlReader& reader);

/// Convex hull, bitangent planes (Sec. 3.1, equations (1)-(3)): 3 equations in (u, v, s, t).
Problem buildConvexHull(const ApplicationInput& in);
/// Perspective silhouette of a swept volume (Sec. 3.2, equations (4)-(5)) in (u, v, t).
Problem buildSweepSilhouette(const ApplicationInput& in);
/// Bisector of two surfaces (Sec. 3.3, equations (6)) in (u, v, s, t), via Cramer's rule.
Problem buildBisector(const ApplicationInput& in);
/// Envelope of a swept surface (Sec. 3.4, equation (4)) in (u, v, t).
Problem buildSweepEnvelope(const ApplicationInput& in);
/// Blending surface (Sec. 3.5, equations (7)-(8)) in (u, v, s, t, a1, a2).
Problem buildBlending(const ApplicationInput& in);

}  // namespace ndc
