/// \file paper_reference.hpp
/// The paper's reference figures (internal to experiments/report/): its Table 1, read at run
/// time from `<reference>/table1.toml` (see ndc::report::referenceDir) for `tab1-degeneracy` and
/// `fig-degeneracy-vs-n`.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace ndc::report::detail {

/// One example of the paper's Table 1, as read from `<reference>/table1.toml`.
struct PaperRow {
  std::string key;        ///< matched against the normalised problem name and file stem
  std::string label;      ///< the paper's example, e.g. "Bisector, Fig. 8(a)"
  std::string family;     ///< the application: bisector, sweep or blending
  std::string highlight;  ///< optional: how the sentences name a row the paper singles out
  int n = 0;              ///< the ambient dimension
  double normal = 0;      ///< normal cells
  double abnormal = 0;    ///< abnormal cells
  double share = 0;       ///< the abnormal share in percent
};

/// The paper's Table 1 from `<reference>/table1.toml` (a `[[row]]` per example, in the paper's
/// order). Throws InputError (one line, naming the file) when it is missing or malformed.
std::vector<PaperRow> loadPaperTable1(const std::filesystem::path& reference);

}  // namespace ndc::report::detail
