// The page assets, inlined at build time (web/CMakeLists.txt generates assets.cpp from
// show.html, show.css, show.js and Debian's three.min.js).
#pragma once

#include <string_view>

namespace dicesim::web {

extern const std::string_view kShowHtml, kShowCss, kShowJs, kThreeJs;
extern const std::string_view kServeHtml, kServeCss, kServeJs;

}  // namespace dicesim::web
