/// \file connection.hpp
/// The connection family (docs/algorithm1.md): builds the k-simplices of the complex from the
/// projected and classified solution cells (paper Sec. 4.1, 4.2, Algorithm 1). See the page
/// \ref connection for the rules and the choices made where the paper is vague.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <variant>

#include "framework/numeric/scalar.hpp"
#include "framework/strategy/registry.hpp"
#include "framework/strategy/strategy.hpp"
#include "strategies/connection/crossing.hpp"

namespace ndc {

/// The paper's "thick volume" baseline (Sec. 4.1, Fig. 3(b)): no classification is used.
/// Every solution cell gets a vertex (its projected point if Newton converged, else the
/// centroid of its closed box). k = 1: an edge for every face-adjacent pair of solution cells.
/// k = 2: for every plaquette `c, c+e_a, c+e_a+e_b, c+e_b` (a < b) of four solution cells a
/// quad, split into two triangles along its shorter diagonal.
class NaiveConnection final {
 public:
  /// The model's name, what it does, its parameters with their defaults and its capabilities
  /// (defined in naive.cpp, next to the model; the family's registry lists it in one line).
  static ModelSpec spec();
  /// The model with a spec's parameter values.
  static NaiveConnection create(const Parameters& parameters);

  /// Builds the naive complex; throws InputError unless k is 1 or 2.
  template <class S>
  ConnectionOutput<S> connect(const ConnectionInput<S>& input) const;
};

/// The paper's connection (Sec. 4.1, 4.2, Algorithm 1).
///
/// 1. Vertices are the projected points of the normal cells only.
/// 2. Face-adjacent normal cells are connected: by an edge (k = 1), by the plaquette rule
///    (k = 2: four mutually face-adjacent normal cells give a quad, two triangles).
/// 3. Dangling normal cells (k = 1: fewer than two edges; k = 2: a boundary edge or no
///    triangle) with a face-adjacent abnormal cell form the set D (Alg. 1 step (2)).
/// 4. For each d in D: the cluster N of face-adjacent normal and abnormal cells, recursively
///    through abnormal cells up to n - 1 layers; the projected centroid of its abnormal
///    points; the tangent space there (Gram-Schmidt of the gradients, then the projected
///    standard basis vectors of largest magnitude); the cluster's dangling points are
///    parameterised over it and joined through the centroid (k = 1: open ends facing each
///    other along the tangent line are matched, nearest first; k = 2: an angular fan).
///
/// Choices beyond the paper (see \ref connection): for k = 1 a normal cell whose normal
/// face-neighbours are not one on each side of its tangent line (a thick set of normal cells)
/// keeps only the nearest neighbour on each side, so normal edges never branch; and cells
/// still open after the pass over D get a second, own cluster (k = 1).
class PaperConnection final {
 public:
  /// Tunable choices; the defaults are the documented ones.
  struct Options {
    /// k = 1: thin thick normal sets along the tangent line (false: the literal rule).
    bool thinThickNormal = true;
    /// Alg. 1 "recursive up to depth of (n - 1) layers": the number of expansions through
    /// abnormal cells is `n - 1 + extraLayers`.
    int extraLayers = 0;
  };

  /// The model's name, what it does, its parameters with their defaults and its capabilities
  /// (defined in paper.cpp, next to the model; the family's registry lists it in one line).
  static ModelSpec spec();
  /// The model with a spec's parameter values.
  static PaperConnection create(const Parameters& parameters);

  PaperConnection() = default;
  explicit PaperConnection(const Options& options) : options_(options) {}
  const Options& options() const { return options_; }

  /// Builds the paper's complex; throws InputError unless k is 1 or 2.
  /// `ambiguousCells` counts normal cells in a thick normal set (k = 1: more than two normal
  /// face-neighbours or two on one side of the tangent line; k = 2: on a non-manifold edge
  /// after the plaquette rule);
  /// `singularCells` counts clusters whose centroid has a rank-deficient Jacobian.
  template <class S>
  ConnectionOutput<S> connect(const ConnectionInput<S>& input) const;

 private:
  Options options_;
};

extern template ConnectionOutput<double> NaiveConnection::connect(
    const ConnectionInput<double>&) const;
extern template ConnectionOutput<Mpfr> NaiveConnection::connect(const ConnectionInput<Mpfr>&) const;
extern template ConnectionOutput<double> PaperConnection::connect(
    const ConnectionInput<double>&) const;
extern template ConnectionOutput<Mpfr> PaperConnection::connect(const ConnectionInput<Mpfr>&) const;

static_assert(ConnectionStrategy<PaperConnection, double>);
static_assert(ConnectionStrategy<PaperConnection, Mpfr>);
static_assert(ConnectionStrategy<NaiveConnection, double>);
static_assert(ConnectionStrategy<NaiveConnection, Mpfr>);

/// A connection model that is none of the variant's own alternatives (a new strategy in one
/// file, or a test-only one): one virtual call per stage, for both scalars.
class DynamicConnection final {
 public:
  template <class T>
  explicit DynamicConnection(T model) : model_(std::make_shared<Holder<T>>(std::move(model))) {}

  template <class S>
  ConnectionOutput<S> connect(const ConnectionInput<S>& input) const {
    return model_->connect(input);
  }

 private:
  struct Model {
    virtual ~Model() = default;
    virtual ConnectionOutput<double> connect(const ConnectionInput<double>& input) const = 0;
    virtual ConnectionOutput<Mpfr> connect(const ConnectionInput<Mpfr>& input) const = 0;
  };
  template <class T>
  struct Holder final : Model {
    explicit Holder(T m) : model(std::move(m)) {}
    ConnectionOutput<double> connect(const ConnectionInput<double>& in) const override {
      return model.connect(in);
    }
    ConnectionOutput<Mpfr> connect(const ConnectionInput<Mpfr>& in) const override {
      return model.connect(in);
    }
    T model;
  };
  std::shared_ptr<const Model> model_;
};

/// The connection family: one variant, dispatched once per stage. Models: PaperConnection,
/// NaiveConnection, CrossingConnection (strategies/connection/crossing.hpp), and any other
/// registered model through DynamicConnection.
using Connection =
    std::variant<PaperConnection, NaiveConnection, CrossingConnection, DynamicConnection>;

/// `model` as a Connection: its own alternative when it has one, else a DynamicConnection.
template <class T>
Connection holdConnection(T model) {
  if constexpr (std::is_constructible_v<Connection, std::in_place_type_t<T>, T> &&
                !std::is_same_v<T, DynamicConnection>)
    return Connection(std::in_place_type<T>, std::move(model));
  else
    return Connection(std::in_place_type<DynamicConnection>, DynamicConnection(std::move(model)));
}

/// A connection factory: the model built with the spec's parameter values.
using ConnectionFactory = Connection (*)(const Parameters& parameters);

/// The connection family's registry (strategies/connection/connection.cpp lists the models;
/// the CLI's `--connection`). Mutable so that tests can register test-only models.
Registry<ConnectionFactory>& connectionRegistry();

/// The names of the registered connection models whose capabilities satisfy `can`, joined by
/// `separator` ("crossing", "paper, naive"); empty when none does. For messages that name the
/// models able to do what the chosen one cannot.
std::string connectionsThat(const std::function<bool(const Capabilities&)>& can,
                            std::string_view separator = ", ");

/// InputError unless `connection` builds manifolds of dimension k (its capabilities), naming
/// the connections that do, if any; `where` prefixes the message ("FILE: "). The pipeline calls
/// it before any work, and each model's connect() again for direct calls.
void requireBuildsK(const ModelSpec& connection, int k, const std::string& where = "");

/// Makes the connection a parsed spec names, with its parameters.
Connection createConnection(const StrategyChoice& choice);
/// Makes the connection of a spec (`paper`, `paper:extra_layers=1`); UsageError on an unknown
/// name, parameter or value.
Connection createConnection(std::string_view spec);

/// Runs the connection stage (one std::visit per stage).
template <class S>
ConnectionOutput<S> connect(const Connection& connection, const ConnectionInput<S>& input) {
  return std::visit([&](const auto& c) { return c.connect(input); }, connection);
}

}  // namespace ndc
