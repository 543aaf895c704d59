"""dicesim.load_scene / toss / Result: the same counts and JSON as the CLI."""
import json

import pytest

from conftest import DIE1, cli_json, require, run_cli, without_timing


def test_import_from_build_python_with_debian_python():
    import subprocess, sys
    p = subprocess.run([sys.executable, "-c", "import dicesim, numpy; print(dicesim.__file__)"],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert "build" in p.stdout and "python" in p.stdout


@pytest.mark.parametrize("args", [
    dict(n=20000, seed=7, threads=2),
    dict(n=3000, seed=1, threads=1, fidelity="static"),
    dict(n=4500, seed=3, threads=2, fidelity="impulse"),  # two blocks of the slow fidelities' loop
])
def test_to_dict_is_cli_json(dicesim, args):
    scene = dicesim.load_scene(DIE1)
    r = dicesim.toss(scene, args["n"], seed=args["seed"], threads=args["threads"], fidelity=args.get("fidelity"))
    cli = ["toss", DIE1, "-n", str(args["n"]), "--seed", str(args["seed"]), "--threads", str(args["threads"])]
    if "fidelity" in args:
        cli += ["--fidelity", args["fidelity"]]
    expected = cli_json(*cli)
    d = r.to_dict()
    assert set(d) == set(expected)  # the same keys, timing included
    assert without_timing(d) == without_timing(expected)
    assert d["elapsed_s"] == pytest.approx(r.elapsed_s)


def test_auto_is_resolved_as_the_cli_does(dicesim):
    # A scene that names no model runs auto: the same pilot, choice and counts as `dicesim toss`.
    caught = "scenes/coins/quarter-caught.toml"
    r = dicesim.toss(dicesim.load_scene(caught), 100000, seed=4, threads=2)
    d = r.to_dict()
    assert d["fidelity_requested"] == "auto" and d["fidelity"] == "paper"
    assert d["pilot"]["candidates"][-1]["adequate"] and d["pilot"]["tosses"] > 0
    expected = cli_json("toss", caught, "-n", "100000", "--seed", "4", "--threads", "2")
    assert without_timing(d) == without_timing(expected)


def test_overrides_are_the_clis_set(dicesim):
    scene = dicesim.load_scene(DIE1, set={"materials.steel.restitution": 0.9, "throw.height.mean": 0.5,
                                          "sim.fidelity": "paper"})
    r = dicesim.toss(scene, 5000, seed=2)
    expected = cli_json("toss", DIE1, "-n", "5000", "--seed", "2", "--set", "materials.steel.restitution=0.9",
                        "--set", "throw.height.mean=0.5", "--set", "sim.fidelity=paper")
    d, e = without_timing(r.to_dict()), without_timing({**expected, "threads": r.threads})
    # Python writes a string value quoted (sim.fidelity="paper"), the CLI took it bare: the overrides'
    # text and the threads differ, the resolved scene is the same.
    assert d.pop("provenance")["scene_sha256"] == e.pop("provenance")["scene_sha256"]
    assert d == e
    # and the override changed something (else the comparison above proves little)
    plain = dicesim.toss(dicesim.load_scene(DIE1), 5000, seed=2)
    assert list(plain.counts) != list(r.counts)


def test_counts_do_not_depend_on_threads(dicesim, die1):
    a = dicesim.toss(die1, 30000, seed=11, threads=1)
    b = dicesim.toss(die1, 30000, seed=11, threads=2)
    assert list(a.counts) == list(b.counts)
    assert a.settled == b.settled


def test_scene_from_toml_equals_file(dicesim, die1):
    text = open(DIE1).read()
    scene = dicesim.scene_from_toml(text, name="die1-text")
    assert scene.path == "die1-text"
    a, b = dicesim.toss(scene, 4000, seed=5), dicesim.toss(die1, 4000, seed=5)
    assert list(a.counts) == list(b.counts)
    assert a.to_dict()["scene"] == "die1-text"


def test_result_arrays(dicesim, die1):
    np = require("numpy")
    r = dicesim.toss(die1, 10000, seed=1)
    assert r.counts.dtype == np.int64 and r.labels.dtype == np.int64
    assert list(r.labels) == sorted(r.labels) == die1.labels
    assert r.counts.sum() == r.settled
    assert r.settled + r.unresolved + r.invalid == r.tosses == 10000
    assert r.p.shape == (len(r.labels),) and r.ci95.shape == (len(r.labels), 2)
    assert abs(r.p.sum() - 1.0) < 1e-12
    assert np.all(r.ci95[:, 0] <= r.p) and np.all(r.p <= r.ci95[:, 1])
    d = r.to_dict()
    assert [f["count"] for f in d["faces"]] == list(r.counts)
    assert r.chi2_uniform == d["chi2_uniform"]
    assert r.chi2_heads_tails is None  # a die
    assert r.corrections == d.get("corrections")  # None until the report has a corrections object
    assert "face" in str(r) and "settled" in repr(r)


def test_info_is_cli_info_json(dicesim, die1):
    assert die1.info() == cli_json("info", DIE1)
    assert die1.info(fidelity="static") == cli_json("info", DIE1, "--fidelity", "static")


def test_target_halfwidth_stops_where_the_cli_does(dicesim, die1):
    r = dicesim.toss(die1, target_halfwidth=0.006, seed=4)
    p = run_cli("toss", DIE1, "--target-halfwidth", "0.006", "--seed", "4", "--json")
    expected = json.loads(p.stdout)
    assert r.tosses == expected["tosses"] and r.tosses % 10000 == 0 and r.tosses > 10000
    assert without_timing(r.to_dict()) == without_timing({**expected, "threads": r.threads})
    assert max(r.ci95[:, 1] - r.ci95[:, 0]) / 2 <= 0.006


def test_progress_is_called_from_the_calling_thread(dicesim, die1):
    import threading
    calls = []
    me = threading.get_ident()

    def progress(done, total):
        assert threading.get_ident() == me
        calls.append((done, total))

    n = 400000
    dicesim.toss(die1, n, threads=2, progress=progress)
    assert calls[-1] == (n, n)
    assert all(a[0] <= b[0] for a, b in zip(calls, calls[1:]))
    assert all(t == n and 0 <= d <= n for d, t in calls)


def test_progress_exception_stops_the_run(dicesim, die1):
    class Stop(Exception):
        pass

    def progress(done, total):
        raise Stop()

    with pytest.raises(Stop):
        dicesim.toss(die1, 10**9, progress=progress)


def test_to_pandas(dicesim, die1):
    require("pandas")
    r = dicesim.toss(die1, 2000)
    df = r.to_pandas()
    assert list(df.columns) == ["face", "count", "p", "lo", "hi"]
    assert list(df["face"]) == list(r.labels) and list(df["count"]) == list(r.counts)
    assert df.attrs["settled"] == r.settled and df.attrs["fidelity"] == "paper"


def test_help_and_docstrings(dicesim):
    for f in (dicesim.load_scene, dicesim.scene_from_toml, dicesim.toss, dicesim.toss_one, dicesim.sweep,
              dicesim.sweep_file):
        assert f.__doc__ and len(f.__doc__) > 100
    assert "toss --json" in dicesim.Result.to_dict.__doc__
    assert issubclass(dicesim.SceneError, ValueError)


def test_stub_names_exist(dicesim):
    import ast
    from conftest import SOURCE_DIR
    tree = ast.parse((SOURCE_DIR / "python/dicesim.pyi").read_text())
    names = {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    assert names >= {"load_scene", "scene_from_toml", "toss", "toss_one", "sweep", "sweep_file", "Scene", "Result",
                     "Sweep", "SceneError"}
    for name in names:
        assert hasattr(dicesim, name), name


def test_a_coin_is_tested_heads_against_tails(dicesim):
    r = dicesim.toss(dicesim.load_scene("scenes/coins/quarter.toml"), 2000, seed=3)
    c = r.chi2_heads_tails
    assert c == r.to_dict()["chi2_heads_tails"] and c["dof"] == 1
    n = dict(zip(r.labels, r.counts))  # heads 1, tails 2, edge 0
    assert abs(c["statistic"] - (n[1] - n[2]) ** 2 / (n[1] + n[2])) < 1e-9
