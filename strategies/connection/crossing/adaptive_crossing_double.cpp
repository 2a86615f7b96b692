// AdaptiveCrossing<double> and CrossingConnection::connect<double>, instantiated here and nowhere
// else: a program may hold only one explicit instantiation definition of a specialization
// ([temp.spec]), so the members live in the role files (*.inl), which only this file and
// adaptive_crossing_mpfr.cpp include: one translation unit per scalar (adaptive_crossing.hpp).
#include "strategies/connection/crossing/adaptive_crossing.hpp"

#include "strategies/connection/crossing/adaptive_crossing.inl"
#include "strategies/connection/crossing/blocks.inl"
#include "strategies/connection/crossing/chord_refinement.inl"
#include "strategies/connection/crossing/face_walk.inl"
#include "strategies/connection/crossing/leaf_certificate.inl"
#include "strategies/connection/crossing/leaf_patches.inl"
#include "strategies/connection/crossing/owned_faces.inl"
#include "strategies/connection/crossing/prefetch.inl"
#include "strategies/connection/crossing/refinement.inl"

namespace ndc::crossing_detail {

template class AdaptiveCrossing<double>;

}  // namespace ndc::crossing_detail

namespace ndc {

template ConnectionOutput<double> CrossingConnection::connect(const ConnectionInput<double>&) const;

}  // namespace ndc
