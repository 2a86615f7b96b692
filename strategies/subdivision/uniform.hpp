/// \file uniform.hpp
/// The `uniform` subdivision model: the paper's 2^n children per level (strategies/subdivision/
/// subdivision.hpp has the tree they share).
#pragma once

#include "framework/strategy/registry.hpp"

namespace ndc {

/// Uniform subdivision (`uniform`), as in the paper: a box is split into 2^n children at once,
/// i.e. only the depths d = 0, n, 2n, ..., n L of the tree are bounded.
class UniformSubdivision final {
 public:
  /// The model's name, sentence and parameters (its registry entry).
  static ModelSpec spec() {
    return {"uniform",
            "As in the paper: 2^n children per level, a box is bounded after every n halvings.",
            {}};
  }

  /// Whether the box at depth `level` of the tree (n variables) is bounded: `level % n == 0`.
  bool boundsAfter(int level, int n) const { return level % n == 0; }
};

}  // namespace ndc
