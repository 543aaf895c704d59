// The fingerprint of a scene as run: SHA-256 of a canonical text of its fully resolved TOML tree
// (after `extends` and `--set`), the same on any machine for the same inputs.
//
// Canonical text: the tree as compact JSON, keys sorted (byte order) at every level, without the
// top-level `name` (a label, not physics; a scene that extends another drops the base's name);
// every number (TOML integer or float) written as an IEEE double in shortest round-trip form, so
// 2000, 2000.0 and 2e3 are one value; a mesh die's `die.mesh` path replaced by "sha256:" and the
// hash of the OBJ file's bytes (the same mesh under another path is the same scene; an edited
// mesh is not); likewise each [[dice]] entry's `scene` path by "sha256:" and the hash of that
// scene's own canonical text (tree_sha256 in scene.cpp). Comments, whitespace, key order, quoting
// and how a table is written (dotted keys, [headers], inline) leave no trace. A key stated at its default value is not the same text as
// the key left out: those hash differently.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <toml++/toml.h>

namespace dicesim {

// The canonical text above; `mesh_text` (the OBJ's bytes, read by load_scene) stands in for die.mesh when non-empty.
std::string canonical_scene_text(const toml::table& resolved, const std::string& mesh_text);
// The hash of the scene load_scene(path, overrides) / parse_scene(text, origin, overrides) loads
// (implemented in scene.cpp, beside the tree). Throws SceneError as they do.
std::string scene_sha256(const std::string& path, const std::vector<std::string>& overrides = {});
std::string scene_text_sha256(const std::string& toml_text, const std::string& origin,
                              const std::vector<std::string>& overrides = {});
// Lower-case hex SHA-256 of `bytes` (OpenSSL libcrypto).
std::string sha256_hex(std::string_view bytes);

}  // namespace dicesim
