// One self-contained HTML page for `dicesim show`: the page assets (web/show.html, show.css,
// show.js) and three.js from Debian's libjs-three, all inlined at build time, with the data.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace dicesim::web {

// page: {"scene": path, "die": die_json(...), "info": info JSON, "toss": toss_json(...) or absent}.
// The page loads nothing: no network, no other file.
std::string show_html(const nlohmann::json& page);

}  // namespace dicesim::web
