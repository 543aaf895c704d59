// dicesim.show: the page `dicesim show` writes, as an object Jupyter displays inline.
#include <fstream>

#include <pybind11/stl.h>

#include "apps/info_json.hpp"
#include "python/bindings.hpp"
#include "sim/body/material_parts.hpp"
#include "web/show_data.hpp"
#include "web/show_page.hpp"

namespace dicesim::py {
namespace {

// The HTML of one page; Jupyter shows it in an iframe (its scripts and styles stay apart from the
// notebook's).
struct ShowPage {
  std::string html;
  std::string repr_html() const {
    std::string esc;
    esc.reserve(html.size() + html.size() / 8);
    for (const char c : html) {
      if (c == '&') esc += "&amp;";
      else if (c == '"') esc += "&quot;";
      else if (c == '<') esc += "&lt;";
      else if (c == '>') esc += "&gt;";
      else esc += c;
    }
    return "<iframe srcdoc=\"" + esc + "\" style=\"width: 100%; height: 640px; border: 1px solid #ddd\"></iframe>";
  }
};

ShowPage show(Scene& scene, std::optional<std::uint64_t> toss, std::uint64_t seed, std::optional<std::string> fidelity) {
  const std::shared_ptr<const DieModel> model = scene.model(fidelity);
  if (model->world)
    throw pb::value_error("show draws one die alone: a toss of several dice or among obstacles cannot be drawn yet (docs/world.md)");
  nlohmann::json page;
  page["scene"] = scene.origin();
  page["die"] = web::die_json(*model, scene.def());
  page["info"] = info_json(scene.origin(), *model, material_parts(scene.def(), scene.origin()));
  if (toss) {
    pb::gil_scoped_release nogil;
    page["toss"] = web::toss_json(*model, seed, *toss);
  }
  return ShowPage{web::show_html(page)};
}

}  // namespace

void register_show(pb::module_& m) {
  pb::class_<ShowPage>(m, "ShowPage",
                       "A self-contained HTML page (three.js inlined; no network): .html is its text, .save(path)\n"
                       "writes it, and Jupyter displays it inline.")
      .def_readonly("html", &ShowPage::html)
      .def("_repr_html_", &ShowPage::repr_html)
      .def("save", [](const ShowPage& p, const std::string& path) {
        std::ofstream f(path, std::ios::binary | std::ios::trunc);
        if (!f) throw pb::value_error("cannot write " + path);
        f << p.html;
        if (!f.flush()) throw pb::value_error("writing " + path + " failed");
      }, pb::arg("path"))
      .def("__str__", [](const ShowPage& p) { return p.html; })
      .def("__repr__", [](const ShowPage& p) { return "<dicesim.ShowPage " + std::to_string(p.html.size()) + " bytes>"; });
  m.def("show", &show, pb::arg("scene"), pb::arg("toss") = pb::none(), pb::arg("seed") = 1, pb::arg("fidelity") = pb::none(),
        "The page `dicesim show` writes: the die in 3-D (turnable, labelled faces, material regions\n"
        "tinted, centre of mass marked) beside `info`'s table; with toss=I, toss number I of a run with\n"
        "`seed` (the very toss toss_one(scene, I, seed) makes) animated, impacts on its timeline and the\n"
        "outcome named. Returns a ShowPage: str(page) / page.html is the HTML, page.save(path) writes\n"
        "it, and in Jupyter the page displays inline.");
}

}  // namespace dicesim::py
