// The connection family's registry, one line per model (docs/algorithm1.md, docs/contracts.md
// 4.2 `--connection`).
#include "strategies/connection/connection.hpp"

#include <string>

#include "framework/util/errors.hpp"

namespace ndc {

namespace {

/// A model's registry entry: its own spec and a factory from the spec's parameters.
template <class Model>
Registry<ConnectionFactory>::Entry entryOf() {
  return {Model::spec(), [](const Parameters& p) { return holdConnection(Model::create(p)); }};
}

}  // namespace

//! [connection-registry]
Registry<ConnectionFactory>& connectionRegistry() {
  static Registry<ConnectionFactory> registry(
      "connection",
      {entryOf<PaperConnection>(), entryOf<NaiveConnection>(), entryOf<CrossingConnection>()});
  return registry;
}
//! [connection-registry]

std::string connectionsThat(const std::function<bool(const Capabilities&)>& can,
                            std::string_view separator) {
  std::string names;
  for (const ModelSpec& model : connectionRegistry().specs())
    if (can(model.capabilities))
      names += (names.empty() ? "" : std::string(separator)) + model.name;
  return names;
}

void requireBuildsK(const ModelSpec& connection, int k, const std::string& where) {
  const Capabilities& can = connection.capabilities;
  if (can.builds(k)) return;
  const std::string others = connectionsThat([k](const Capabilities& c) { return c.builds(k); });
  const std::string range = can.minK == can.maxK
                                ? std::to_string(can.minK)
                                : std::to_string(can.minK) + ".." + std::to_string(can.maxK);
  throw InputError(
      where + "the " + connection.name + " connection builds k = " + range +
      "; this problem has k = " + std::to_string(k) + " (n - m)" +
      (others.empty() ? ", which no connection builds yet" : "; use --connection " + others));
}

Connection createConnection(const StrategyChoice& choice) {
  return connectionRegistry().find(choice.name).create(choice.parameters);
}

Connection createConnection(std::string_view spec) {
  return createConnection(connectionRegistry().parse(spec));
}

}  // namespace ndc
