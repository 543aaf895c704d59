#include "sim/scene/scene_hash.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>

#include <nlohmann/json.hpp>
#include <openssl/evp.h>

namespace dicesim {
namespace {

nlohmann::json to_json(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table: {
      nlohmann::json j = nlohmann::json::object();  // std::map: keys sorted
      for (auto&& [k, v] : *n.as_table()) j[std::string(k.str())] = to_json(v);
      return j;
    }
    case toml::node_type::array: {
      nlohmann::json j = nlohmann::json::array();
      for (const toml::node& e : *n.as_array()) j.push_back(to_json(e));
      return j;
    }
    case toml::node_type::string: return n.as_string()->get();
    case toml::node_type::integer: return static_cast<double>(n.as_integer()->get());
    case toml::node_type::floating_point: return n.as_floating_point()->get();
    case toml::node_type::boolean: return n.as_boolean()->get();
    default: {  // dates and times: no scene key takes one, but they still must hash as written
      std::ostringstream s;
      n.visit([&s](auto&& v) { s << v; });
      return "toml:" + s.str();
    }
  }
}

}  // namespace

std::string canonical_scene_text(const toml::table& resolved, const std::string& mesh_text) {
  nlohmann::json j = to_json(resolved);
  j.erase("name");
  if (!mesh_text.empty() && j.contains("die") && j["die"].is_object() && j["die"].contains("mesh"))
    j["die"]["mesh"] = "sha256:" + sha256_hex(mesh_text);
  // Non-finite numbers (TOML allows inf and nan) have no JSON form: dump() writes null, which would
  // make inf and nan one value; they are written as strings instead, here, before dumping.
  std::function<void(nlohmann::json&)> fix = [&](nlohmann::json& v) {
    if (v.is_number_float() && !std::isfinite(v.get<double>())) {
      const double d = v.get<double>();
      v = std::isnan(d) ? "nan" : d > 0 ? "inf" : "-inf";
    } else if (v.is_structured()) {
      for (auto& e : v) fix(e);
    }
  };
  fix(j);
  return j.dump();
}

std::string sha256_hex(std::string_view bytes) {
  std::array<unsigned char, EVP_MAX_MD_SIZE> md{};
  unsigned int len = 0;
  EVP_Digest(bytes.data(), bytes.size(), md.data(), &len, EVP_sha256(), nullptr);
  std::string hex;
  char b[3];
  for (unsigned int i = 0; i < len; ++i) {
    std::snprintf(b, sizeof b, "%02x", md[i]);
    hex += b;
  }
  return hex;
}

}  // namespace dicesim
