"""dicesim.fit: the same fit as `dicesim fit --json`, several data sets, bad input."""
import pytest

from conftest import DIE1, cli_json

COUNTS = {1: 80, 2: 83, 3: 84, 4: 85, 5: 81, 6: 87}


def test_fit_equals_the_cli(dicesim, tmp_path):
    csv = tmp_path / "counts.csv"
    csv.write_text("face,count\n" + "".join(f"{k},{v}\n" for k, v in COUNTS.items()))
    r = dicesim.fit(DIE1, str(csv), {"materials.steel.density": (3000, 20000)}, n=4000, fidelity="static", threads=2)
    cli = cli_json("fit", DIE1, "--data", str(csv), "--param", "materials.steel.density=3000:20000", "-n", "4000",
                   "--fidelity", "static")
    for k in ("params", "fitted", "gof", "simulated_tosses", "rounds"):
        assert r[k] == cli[k], k
    p = r["params"][0]
    assert p["key"] == "materials.steel.density"
    assert p["ci95"][0] <= p["estimate"] <= p["ci95"][1]
    assert [f["label"] for f in r["fitted"]] == [1, 2, 3, 4, 5, 6]
    assert abs(sum(f["p"] for f in r["fitted"]) - 1) < 1e-12
    # a dict of counts and a Scene object give the same fit
    same = dicesim.fit(dicesim.load_scene(DIE1), COUNTS, ["materials.steel.density=3000:20000"], n=4000,
                       fidelity="static", threads=1)
    assert same["params"] == r["params"]


def test_fit_two_data_sets_jointly(dicesim):
    r = dicesim.fit([DIE1, DIE1], [COUNTS, COUNTS], {"materials.steel.density": (3000, 20000)}, n=4000,
                    fidelity="static")
    assert len(r["data"]) == 2 and len(r["fitted"]) == 12
    assert r["gof"]["dof"] == 5 + 5 - 1
    seen = []
    r1 = dicesim.fit(DIE1, COUNTS, {"materials.steel.density": (3000, 20000)}, n=4000, fidelity="static",
                     progress=lambda done, total: seen.append((done, total)))
    # Both data sets are tossed at every evaluation; the joint fit's rounds (a box widened when a
    # confidence set reaches it) need not be the single fit's, so the totals are not a fixed ratio.
    assert r["simulated_tosses"] % 2 == 0 and r["simulated_tosses"] > r1["simulated_tosses"]
    assert seen and seen[-1][0] == seen[-1][1] == r1["simulated_tosses"]


def test_fit_bad_input(dicesim):
    with pytest.raises(dicesim.SceneError, match="7"):
        dicesim.fit(DIE1, {1: 5, 7: 3}, {"materials.steel.density": (3000, 20000)}, n=2000, fidelity="static")
    with pytest.raises(dicesim.SceneError, match="LO"):
        dicesim.fit(DIE1, COUNTS, {"floor.restitution": (0.9, 0.1)}, n=2000, fidelity="static")
    with pytest.raises(dicesim.SceneError, match="nothing"):
        dicesim.fit(DIE1, COUNTS, ["floor.nothing=0:1"], n=2000, fidelity="static")
    with pytest.raises(ValueError, match="same length"):
        dicesim.fit([DIE1], [COUNTS, COUNTS], ["floor.restitution=0.1:0.9"], n=2000)
    with pytest.raises(ValueError, match="TOML text"):
        dicesim.fit(dicesim.scene_from_toml("[materials.m]\ndensity = 1000.0\n[die]\nmaterial = \"m\"\n"), COUNTS, ["floor.restitution=0.1:0.9"])


def test_fit_provenance_names_every_data_sets_scene(dicesim):
    # Issue 35: a fit's provenance hashes the scene as simulated, the data set's own overrides
    # included; a joint fit names each data set's scene, overrides and hash.
    heavy = dicesim.load_scene(DIE1, set={"floor.restitution": 0.4})
    r = dicesim.fit([heavy, DIE1], [COUNTS, COUNTS], {"materials.steel.density": (3000, 20000)}, n=2000,
                    fidelity="static")
    plain = dicesim.fit(DIE1, COUNTS, {"materials.steel.density": (3000, 20000)}, n=2000, fidelity="static")
    first, second = r["data"]
    assert "floor.restitution=0.4" in first["overrides"]
    assert "floor.restitution=0.4" not in second["overrides"]
    assert first["scene_sha256"] != second["scene_sha256"]
    assert second["scene_sha256"] == plain["data"][0]["scene_sha256"]
    # the top-level provenance is the first data set's scene as simulated
    assert r["provenance"]["scene_sha256"] == first["scene_sha256"]
    assert r["provenance"]["overrides"] == first["overrides"]
    assert plain["provenance"]["scene_sha256"] == second["scene_sha256"]
