/// \file registry.hpp
/// Strategy registries (docs/adding-a-strategy.md): each strategy family lists its models in one
/// registry, and each model declares its name, what it does and its parameters with defaults.
/// The family's names, its factory, the error messages for unknown names and parameters, the
/// CLI help, the experiment runner's validation, the tests that loop over all strategies and
/// the strategy table of the docs all read the registry.
///
/// A strategy is chosen by a *spec*: its name, optionally followed by parameters,
/// `paper:extra_layers=2,thin_thick_normal=false` (docs/contracts.md 4.2). Parameters are
/// integers, reals or booleans; every parameter has a default, so a spec lists only what it
/// changes, and the values used (defaults included) are recorded in `summary.json`.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "framework/util/errors.hpp"

namespace ndc {

/// The type of a strategy parameter.
enum class ParameterType { kInteger, kReal, kBoolean };

/// One parameter a strategy model declares.
struct ParameterSpec {
  std::string name;  ///< the key in a spec, snake_case
  ParameterType type = ParameterType::kInteger;
  double defaultValue = 0;  ///< booleans: 0 or 1
  double min = 0, max = 0;  ///< accepted range (inclusive) of integers and reals
  std::string doc;          ///< one sentence: what it changes
};

/// The parameter values of one strategy: every declared parameter, in declaration order, with
/// its default unless the spec set it.
class Parameters {
 public:
  Parameters() = default;
  explicit Parameters(const std::vector<ParameterSpec>& specs);

  /// The value of `name`; std::logic_error when the model did not declare it (a bug).
  double real(std::string_view name) const;
  int integer(std::string_view name) const { return static_cast<int>(real(name)); }
  bool boolean(std::string_view name) const { return real(name) != 0; }

  /// Sets a declared parameter from its text (`2`, `0.5`, `true`); UsageError naming `where`
  /// when the text is no value of the parameter's type or is out of its range.
  void set(std::string_view name, std::string_view text, const std::string& where);

  /// `{"extra_layers": 0, "thin_thick_normal": true}` (booleans as JSON booleans).
  std::string json() const;
  /// `extra_layers=0,thin_thick_normal=true`; empty without parameters.
  std::string text() const;
  bool empty() const { return values_.empty(); }

 private:
  std::vector<std::pair<ParameterSpec, double>> values_;
};

/// What a model can do, declared once with its spec; the pipeline, the CLI, Python and the
/// report ask for a capability, never for a model's name. The defaults are a model that only
/// builds a complex (the other families have no capabilities to declare).
struct Capabilities {
  /// Connection: proves the topology of its complex (records `topology.certified`, which the
  /// pipeline otherwise marks as not proven).
  bool certifies = false;
  /// Connection: refines cells adaptively below the grid (reads ConnectionInput::refine,
  /// maxLevel and refineSeconds), so `--max-depth` and `--tolerance` mean something.
  bool refines = false;
  /// Connection: the manifold dimensions k it builds, minK..maxK.
  int minK = 1, maxK = 2;

  /// Whether it builds manifolds of dimension k.
  bool builds(int k) const { return k >= minK && k <= maxK; }
};

/// What a registry says about one model.
struct ModelSpec {
  std::string name;
  std::string doc;  ///< one sentence: what the model does, with the paper's words
  std::vector<ParameterSpec> parameters;
  Capabilities capabilities = {};
};

/// A parsed strategy spec: the model's name and its parameter values.
struct StrategyChoice {
  std::string name;
  Parameters parameters;
};

/// Parses a spec against a family's models (Registry::parse).
StrategyChoice parseStrategySpec(std::string_view spec, const std::string& family,
                                 const std::vector<ModelSpec>& models);
/// "unknown FAMILY strategy 'NAME' (known: a, b, c)".
std::string unknownModelMessage(const std::string& family, std::string_view name,
                                const std::vector<std::string>& known);
/// Throws std::logic_error when `name` is no `[a-z][a-z0-9-]*` or is already in `taken`.
void checkModelName(const std::string& family, const std::string& name,
                    const std::vector<std::string>& taken);

/// The registry of one strategy family: its models in order, each with a factory `Factory`
/// (a function pointer or a small struct of them; the family's header says which).
template <class Factory>
class Registry {
 public:
  struct Entry {
    ModelSpec spec;
    Factory create;
  };

  /// `family` names the family in messages ("connection", "bounding", ...).
  Registry(std::string family, std::vector<Entry> entries) : family_(std::move(family)) {
    for (Entry& e : entries) add(std::move(e));
  }

  /// Adds a model (the test tree registers test-only models so); std::logic_error when the
  /// name is taken or is no valid name.
  void add(Entry entry) {
    checkModelName(family_, entry.spec.name, names());
    entries_.push_back(std::move(entry));
  }

  /// Removes the model called `name` (the test tree unregisters test-only models so that the
  /// tests which loop over a family see its own models); false when there is none.
  bool remove(std::string_view name) {
    return std::erase_if(entries_, [&](const Entry& e) { return e.spec.name == name; }) > 0;
  }

  const std::string& family() const { return family_; }
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const Entry& e : entries_) out.push_back(e.spec.name);
    return out;
  }
  std::vector<ModelSpec> specs() const {
    std::vector<ModelSpec> out;
    for (const Entry& e : entries_) out.push_back(e.spec);
    return out;
  }

  /// The model called `name`; UsageError "unknown connection strategy 'x' (known: ...)".
  const Entry& find(std::string_view name) const {
    for (const Entry& e : entries_)
      if (e.spec.name == name) return e;
    throw UsageError(unknownModelMessage(family_, name, names()));
  }

  /// Parses `name[:key=value,...]`; UsageError on an unknown name, key or bad value.
  StrategyChoice parse(std::string_view spec) const {
    return parseStrategySpec(spec, family_, specs());
  }

  /// The parameter values of `name` with their defaults (UsageError on an unknown name).
  Parameters defaults(std::string_view name) const {
    return Parameters(find(name).spec.parameters);
  }

 private:
  std::string family_;
  std::vector<Entry> entries_;
};

/// The models as the CLI help lists them: `a, b (default), c`, then one line per parameter
/// `  b:key=VALUE  doc (default D, range)`.
std::string registryHelp(const std::vector<ModelSpec>& models, std::string_view defaultName);
/// The models as a Markdown table (docs/adding-a-strategy.md "The strategies"): model,
/// parameters with defaults, what it does.
std::string registryMarkdown(const std::string& family, const std::vector<ModelSpec>& models);

}  // namespace ndc
