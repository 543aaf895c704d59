"""dicesim.sweep: common random numbers, the same counts as `dicesim sweep`."""
from conftest import DIE1, cli_json, require


def test_sweep_counts_equal_the_cli(dicesim):
    scene = dicesim.load_scene(DIE1)
    s = dicesim.sweep(scene, "floor.restitution", [0.3, 0.6, 0.9], 3000, seed=2, threads=2)
    cli = cli_json("sweep", DIE1, "--param", "floor.restitution", "--values", "0.3,0.6,0.9", "-n", "3000",
                   "--seed", "2")
    assert len(s) == len(cli["points"]) == 3
    for r, p in zip(s.points, cli["points"]):
        assert [f["count"] for f in r.to_dict()["faces"]] == [f["count"] for f in p["faces"]]
        assert (r.settled, r.unresolved, r.invalid) == (p["settled"], p["unresolved"], p["invalid"])
    assert s.values.tolist() == [0.3, 0.6, 0.9]
    # each point is the toss of the scene with that override, at the same indices
    one = dicesim.toss(dicesim.load_scene(DIE1, set={"floor.restitution": 0.6}), 3000, seed=2)
    assert list(one.counts) == list(s[1].counts)
    assert list(s[0].counts) != list(s[2].counts)


def test_sweep_template_and_spec_text(dicesim):
    scene = dicesim.load_scene(DIE1, set={"die.material": "steel"})
    s = dicesim.sweep(scene, "die.regions", "1/3:2/3:1/3", 500, scale=0.03, shift=-0.015,
                      template='[{ material = "aluminium", cuts = [{ normal = [0, 0, 1], offset = {} }] }]')
    assert len(s) == 2 and abs(s.values[0] - 1 / 3) < 1e-15
    assert s.overrides[0][-1].startswith("die.regions=[{ material")


def test_sweep_to_pandas_long_form(dicesim, die1):
    require("pandas")
    s = dicesim.sweep(die1, "throw.height.mean", [0.5, 1.0], 1000)
    df = s.to_pandas()
    assert list(df.columns) == ["x", "settled", "face", "count", "p", "lo", "hi"]
    assert len(df) == 2 * len(die1.labels)
    assert df.groupby("x")["count"].sum().tolist() == [r.settled for r in s.points]
    assert df.attrs["key"] == "throw.height.mean"


def test_sweep_file_equals_the_cli(dicesim):
    path = "scenes/paper/sweeps/volume-ratio.toml"
    s = dicesim.sweep_file(path, n=200, threads=2)
    cli = cli_json("sweep", path, "-n", "200")
    assert s.title == cli["title"] and len(s) == len(cli["points"]) == 30
    assert s.values.tolist() == [p["x"] for p in cli["points"]]
    assert s.point_labels == [p["label"] for p in cli["points"]]
    for r, p in zip(s.points, cli["points"]):
        assert [f["count"] for f in r.to_dict()["faces"]] == [f["count"] for f in p["faces"]]
        assert r.seed == cli["seed"] and r.tosses == 200
