// The connection family's factory (docs/algorithm1.md, docs/contracts.md 4.2 `--connection`).
#include "strategies/connection/connection.hpp"

#include <string>

#include "framework/core/errors.hpp"

namespace ndc {

//! [connection-registry]
Registry<ConnectionFactory>& connectionRegistry() {
  static Registry<ConnectionFactory> registry(
      "connection",
      {{{"paper",
         "The paper's connection (Sec. 4.1, 4.2): normal cells joined through shared faces, "
         "abnormal cells repaired in their tangent space.",
         {{"extra_layers", ParameterType::kInteger, 0, 0, 8,
           "expansions through abnormal cells beyond the paper's n - 1 layers"},
          {"thin_thick_normal", ParameterType::kBoolean, 1, 0, 1,
           "k = 1: thin thick normal sets along the tangent line (false: the literal rule)"}}},
        [](const Parameters& p) {
          return holdConnection(PaperConnection({.thinThickNormal = p.boolean("thin_thick_normal"),
                                                 .extraLayers = p.integer("extra_layers")}));
        }},
       {{"naive",
         "The thick-volume baseline (Sec. 4.1, Fig. 3(b)): every solution cell joined "
         "to its face neighbours, no classification.",
         {}},
        [](const Parameters&) { return holdConnection(NaiveConnection{}); }},
       {{"crossing",
         "Dual contouring on the crossings of M with cell faces, certified and refined on a "
         "2^n-tree (docs/crossing.md, docs/certificate.md).",
         {{"max_face_depth", ParameterType::kInteger, 20, 1, 40,
           "halvings per free axis of a face whose crossing is not proven unique"}}},
        [](const Parameters& p) {
          CrossingConnection c;
          c.maxFaceDepth = p.integer("max_face_depth");
          return holdConnection(c);
        }}});
  return registry;
}
//! [connection-registry]

Connection createConnection(const StrategyChoice& choice) {
  return connectionRegistry().find(choice.name).create(choice.parameters);
}

Connection createConnection(std::string_view spec) {
  return createConnection(connectionRegistry().parse(spec));
}

}  // namespace ndc
