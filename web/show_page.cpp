// Fills web/show.html's placeholders with the inlined assets and the data (show_page.hpp).
#include "web/show_page.hpp"

#include <string_view>

#include "web/assets.hpp"

namespace dicesim::web {
namespace {

std::string escape_html(std::string_view s) {
  std::string out;
  for (const char c : s) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else out += c;
  }
  return out;
}

}  // namespace

std::string show_html(const nlohmann::json& page) {
  // In a <script> element only "</" can end it early: "<\/" is the same JSON string.
  std::string data = page.dump();
  for (std::size_t p = data.find("</"); p != std::string::npos; p = data.find("</", p + 3)) data.replace(p, 2, "<\\/");
  std::string title = "dicesim show";
  if (page.contains("scene")) title += " " + page["scene"].get<std::string>();
  if (page.contains("toss")) title += " --toss " + std::to_string(page["toss"]["index"].get<std::uint64_t>());
  const std::pair<std::string_view, std::string_view> fills[] = {
      {"@TITLE@", {}}, {"@CSS@", kShowCss}, {"@DATA@", {}}, {"@THREE@", kThreeJs}, {"@SHOW@", kShowJs}};
  const std::string escaped_title = escape_html(title);
  std::string out;
  out.reserve(kShowHtml.size() + kThreeJs.size() + kShowJs.size() + kShowCss.size() + data.size());
  std::size_t from = 0;
  for (const auto& [key, value] : fills) {  // in the template's order, each once
    const std::size_t at = kShowHtml.find(key, from);
    out.append(kShowHtml.substr(from, at - from));
    if (key == "@TITLE@") out += escaped_title;
    else if (key == "@DATA@") out += data;
    else out.append(value);
    from = at + key.size();
  }
  out.append(kShowHtml.substr(from));
  return out;
}

}  // namespace dicesim::web
