/// \file embedded.hpp
/// The files of the viewer page that the build embeds into the binary (experiments/view/embed.cmake
/// generates their definitions from experiments/view/web/), so that `ndcontour view` reads no
/// file at run time.
#pragma once

#include <string_view>

namespace ndc::view::embedded {

/// `web/viewer.html`: the page, with the markers that writeViewer replaces by scripts.
std::string_view pageHtml();

/// `web/viewer.js`: the page's own script (projection, controls, legend, `window.ndcView`).
std::string_view pageJs();

/// three.js (`web/node_modules/three/build/three.min.js`, pinned in `web/package-lock.json`);
/// empty when the build did not find it (`scripts/setup.sh` runs `npm ci` there).
std::string_view threeJs();

}  // namespace ndc::view::embedded
