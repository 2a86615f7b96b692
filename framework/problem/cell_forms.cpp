/// \file cell_forms.cpp
/// CellForms: the per-patch root Bernstein forms, built lazily.
#include "framework/problem/cell_forms.hpp"

#include <utility>

namespace ndc {

template <class S>
CellForms<S>::CellForms(std::span<const Expression> equations, const Grid& grid, Box<S> domain,
                        int rootLevel)
    : equations_(equations),
      grid_(grid),
      domain_(std::move(domain)),
      rootLevel_(rootLevel),
      patch_(static_cast<std::size_t>(grid.n)) {}

template <class S>
const std::vector<Bernstein<S>>& CellForms<S>::root(std::span<const std::int32_t> index,
                                                    int level) {
  // The patch's key in mixed radix 2^rootLevel: at most n * rootLevel bits (Grid::fits).
  CellKey key = 0;
  for (int j = 0; j < grid_.n; ++j) {
    patch_[j] = index[j] >> (level - rootLevel_);
    key = (key << rootLevel_) | static_cast<CellKey>(patch_[j]);
  }
  auto it = forms_.find(key);
  if (it != forms_.end()) return it->second;
  const Box<S> box = rootLevel_ == 0
                         ? domain_
                         : cellBox<S>(Grid{grid_.n, rootLevel_, grid_.domain}, domain_, patch_);
  std::vector<Bernstein<S>> forms;
  forms.reserve(equations_.size());
  for (const Expression& e : equations_) forms.push_back(e.template toBernstein<S>(box));
  return forms_.emplace(key, std::move(forms)).first->second;
}

template class CellForms<double>;
template class CellForms<Mpfr>;

}  // namespace ndc
