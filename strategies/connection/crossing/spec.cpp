// The crossing connection as its registry sees it: name, parameters with their defaults (the
// model's own member initialisers) and capabilities (docs/crossing.md, docs/certificate.md).
#include "strategies/connection/crossing.hpp"

namespace ndc {

ModelSpec CrossingConnection::spec() {
  const CrossingConnection defaults;
  return {"crossing",
          "Dual contouring on the crossings of M with cell faces, certified and refined on a "
          "2^n-tree (docs/crossing.md, docs/certificate.md).",
          {{"max_face_depth", ParameterType::kInteger, static_cast<double>(defaults.maxFaceDepth),
            1, 40, "halvings per free axis of a face whose crossing is not proven unique"}},
          {.certifies = true, .refines = true, .minK = 1, .maxK = 64}};
}

CrossingConnection CrossingConnection::create(const Parameters& parameters) {
  CrossingConnection c;
  c.maxFaceDepth = parameters.integer("max_face_depth");
  return c;
}

}  // namespace ndc
