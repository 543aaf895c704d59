// dicesim.Scene, load_scene, scene_from_toml: a scene loaded and compiled as the CLI does it.
#include <cmath>
#include <sstream>

#include <pybind11/stl.h>

#include "sim/scene/scene_hash.hpp"
#include "apps/info_json.hpp"
#include "apps/report.hpp"
#include "python/bindings.hpp"
#include "sim/scene/fidelity.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/body/material_parts.hpp"
#include "sim/study/auto_pilot.hpp"
#include "sim/models/compile.hpp"

namespace dicesim::py {
namespace {

// A Python value as TOML text for a `--set KEY=VALUE` override. str goes through verbatim, as on
// the command line (TOML if it parses, else a bare string: "impulse", "[0, 0, 1]").
std::string toml_text(const pb::handle& v) {
  if (pb::isinstance<pb::str>(v)) return v.cast<std::string>();
  if (pb::isinstance<pb::bool_>(v)) return v.cast<bool>() ? "true" : "false";
  if (pb::isinstance<pb::int_>(v)) return pb::str(v).cast<std::string>();
  if (pb::isinstance<pb::float_>(v)) {
    const double x = v.cast<double>();
    if (std::isnan(x)) return "nan";
    if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
    return pb::repr(v).cast<std::string>();  // shortest text that reads back as the same double
  }
  if (pb::isinstance<pb::list>(v) || pb::isinstance<pb::tuple>(v) || pb::hasattr(v, "tolist")) {
    pb::object seq = pb::hasattr(v, "tolist") ? v.attr("tolist")() : pb::reinterpret_borrow<pb::object>(v);
    if (!pb::isinstance<pb::list>(seq) && !pb::isinstance<pb::tuple>(seq)) return toml_text(seq);  // numpy scalar
    std::string out = "[";
    bool first = true;
    for (const pb::handle item : seq) {
      if (!first) out += ", ";
      out += toml_text(item);
      first = false;
    }
    return out + "]";
  }
  throw pb::type_error("cannot write a " + pb::str(pb::type::of(v).attr("__name__")).cast<std::string>() +
                       " as a TOML value; pass the TOML text as a str");
}

// `set=`: a dict {key: value} or an iterable of "KEY=VALUE" strings, in order.
std::vector<std::string> overrides_of(const pb::object& set) {
  std::vector<std::string> out;
  if (set.is_none()) return out;
  if (pb::isinstance<pb::dict>(set)) {
    for (const auto& [k, v] : set.cast<pb::dict>()) out.push_back(pb::str(k).cast<std::string>() + "=" + toml_text(v));
    return out;
  }
  if (pb::isinstance<pb::str>(set)) return {set.cast<std::string>()};
  for (const pb::handle item : set) out.push_back(pb::str(item).cast<std::string>());
  return out;
}

pb::object json_to_python(const nlohmann::json& j) {
  return pb::module_::import("json").attr("loads")(j.dump());
}

}  // namespace

std::vector<std::string> fidelity_override(const std::optional<std::string>& fidelity) {
  if (!fidelity) return {};
  if (!parse_fidelity(*fidelity))
    throw SceneError("fidelity", "", "", "'" + *fidelity + "' is not a fidelity; " + kFidelityChoices);
  return {"sim.fidelity=\"" + *fidelity + "\""};  // as SceneArgs::load (apps/cli.cpp)
}

std::shared_ptr<Scene> scene_arg(const pb::handle& scene) {
  if (pb::isinstance<Scene>(scene)) return scene.cast<std::shared_ptr<Scene>>();
  if (pb::isinstance<pb::str>(scene) || pb::hasattr(scene, "__fspath__"))
    return Scene::from_path(pb::str(pb::module_::import("os").attr("fspath")(scene)).cast<std::string>(), {});
  throw pb::type_error("scene must be a dicesim.Scene or a path (str or os.PathLike), got " +
                       pb::str(pb::type::of(scene).attr("__name__")).cast<std::string>());
}

std::optional<std::uint64_t> count_arg(const pb::handle& n, const char* name) {
  if (n.is_none()) return std::nullopt;
  const std::string text = pb::repr(n).cast<std::string>();
  if (pb::isinstance<pb::bool_>(n)) throw pb::type_error(std::string(name) + " must be a whole number, got " + text);
  pb::object whole;
  if (pb::isinstance<pb::float_>(n)) {
    if (!n.attr("is_integer")().cast<bool>())
      throw pb::value_error(std::string(name) + " must be a whole number (100000, 1e5), got " + text);
    whole = pb::int_(pb::reinterpret_borrow<pb::object>(n));
  } else if (PyIndex_Check(n.ptr())) {  // int, numpy integers
    whole = pb::reinterpret_steal<pb::object>(PyNumber_Index(n.ptr()));
    if (!whole) throw pb::error_already_set();
  } else {
    throw pb::type_error(std::string(name) + " must be a whole number (int, or a float such as 1e5), got " + text);
  }
  if (whole < pb::int_(0) || whole > pb::int_(1ULL << 62))
    throw pb::value_error(std::string(name) + " must be in [0, 2^62], got " + text);
  return whole.cast<std::uint64_t>();
}

std::shared_ptr<Scene> Scene::from_path(std::string path, std::vector<std::string> overrides) {
  auto s = std::make_shared<Scene>();
  s->origin_ = std::move(path);
  s->overrides_ = std::move(overrides);
  s->def_ = load_scene(s->origin_, s->overrides_);
  s->model_ = std::make_shared<const DieModel>(compile(s->def_, s->origin_));
  return s;
}

std::shared_ptr<Scene> Scene::from_text(std::string text, std::string origin, std::vector<std::string> overrides) {
  auto s = std::make_shared<Scene>();
  s->origin_ = std::move(origin);
  s->text_ = std::move(text);
  s->overrides_ = std::move(overrides);
  s->def_ = parse_scene(*s->text_, s->origin_, s->overrides_);
  s->model_ = std::make_shared<const DieModel>(compile(s->def_, s->origin_));
  return s;
}

std::string Scene::sha256_with(const std::vector<std::string>& extra) const {
  std::vector<std::string> all = overrides_;
  all.insert(all.end(), extra.begin(), extra.end());
  return text_ ? scene_text_sha256(*text_, origin_, all) : scene_sha256(origin_, all);
}

SceneDef Scene::load_with(const std::vector<std::string>& extra) const {
  std::vector<std::string> all = overrides_;
  all.insert(all.end(), extra.begin(), extra.end());
  return text_ ? parse_scene(*text_, origin_, all) : load_scene(origin_, all);
}

std::shared_ptr<const DieModel> Scene::model(const std::optional<std::string>& fidelity) {
  if (!fidelity) return model_;
  auto it = by_fidelity_.find(*fidelity);
  if (it != by_fidelity_.end()) return it->second;
  auto m = std::make_shared<const DieModel>(compile(load_with(fidelity_override(fidelity)), origin_));
  by_fidelity_.emplace(*fidelity, m);
  return m;
}

void register_scene(pb::module_& m) {
  pb::class_<Scene, std::shared_ptr<Scene>>(m, "Scene",
                                            "A scene loaded, validated and compiled into the immutable die model that\n"
                                            "tosses read. Make one with load_scene() or scene_from_toml().")
      .def_property_readonly("path", &Scene::origin,
                             "The scene file as given (or the name given to scene_from_toml); reports call it 'scene'.")
      .def_property_readonly("overrides", &Scene::overrides, "The overrides applied, as 'KEY=VALUE' texts in order.")
      .def_property_readonly("name", [](const Scene& s) { return s.def().name; }, "The scene's `name` key.")
      .def_property_readonly(
          "fidelity", [](Scene& s) { return std::string(to_string(s.model()->fidelity)); },
          "The physical model tosses use (what 'auto' resolved to).")
      .def_property_readonly(
          "labels",
          [](Scene& s) {
            return s.model()->outcome_labels;  // distinct, ascending
          },
          "The outcome labels: distinct face labels, ascending (the order of Result.counts).")
      .def(
          "info",
          [](Scene& s, std::optional<std::string> fidelity) {
            DieModel m = *s.model(fidelity);
            const FidelityPilot pilot = resolve_auto(m, precision_of_run(m, 100000), resolve_threads(0));  // as `dicesim info`
            nlohmann::json j = info_json(s.origin(), m, material_parts(s.def(), s.origin()));
            j["pilot"] = pilot_json(pilot);
            if (j["pilot"].is_object()) j["pilot"].erase("seconds");  // as `dicesim info --json`
            return json_to_python(j);
          },
          pb::arg("fidelity") = pb::none(),
          "What the scene compiles to, as a dict: exactly `dicesim info SCENE --json`'s object (mass,\n"
          "com, inertia, principal_moments, principal_axes, faces, corners, fidelity, rest, ...).")
      .def("__repr__", [](Scene& s) {
        return "<dicesim.Scene " + s.origin() + " (" + to_string(s.model()->fidelity) + ")>";
      });

  m.def(
      "load_scene",
      [](const std::string& path, const pb::object& set) { return Scene::from_path(path, overrides_of(set)); },
      pb::arg("path"), pb::arg("set") = pb::none(),
      "Reads a scene file (TOML), applies the overrides in `set` and compiles the die.\n"
      "`set` is a dict {\"materials.steel.restitution\": 0.9, \"sim.fidelity\": \"impulse\"} or a list of\n"
      "'KEY=VALUE' texts: each is the command line's `--set KEY=VALUE` (numbers, bools and lists are\n"
      "written as TOML; a str goes through as TOML text, or a bare string if it is not TOML).\n"
      "Raises SceneError (a ValueError) naming the file, key, value and allowed range.");
  m.def(
      "scene_from_toml",
      [](const std::string& text, const pb::object& set, const std::string& name) {
        return Scene::from_text(text, name, overrides_of(set));
      },
      pb::arg("text"), pb::arg("set") = pb::none(), pb::arg("name") = "<string>",
      "The same as load_scene() for TOML text in memory; `name` stands for the file in errors and\n"
      "reports; `extends` paths are relative to the current directory.");
}

}  // namespace dicesim::py
