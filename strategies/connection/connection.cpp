// The connection family's factory (docs/algorithm1.md, docs/contracts.md 4.2 `--connection`).
#include "strategies/connection/connection.hpp"

#include <string>

#include "framework/core/errors.hpp"

namespace ndc {

//! [connection-factory]
Connection createConnection(std::string_view name) {
  if (name == "paper") return PaperConnection{};
  if (name == "naive") return NaiveConnection{};
  if (name == "crossing") return CrossingConnection{};
  throw InputError("unknown connection '" + std::string(name) +
                   "' (expected paper, naive or crossing)");
}
//! [connection-factory]

}  // namespace ndc
