"""dicesim.power: the dict of `dicesim power --json`, the same numbers, and its bad input."""
import pytest

from conftest import DIE1, cli_json

FAIR = "scenes/fair.toml"
SMALL = dict(n=20000, replicates=1000, bootstrap=200, seed=3)


def small_cli(*args):
    return cli_json("power", *args, "-n", "20000", "--replicates", "1000", "--bootstrap", "200", "--seed", "3")


def test_power_against_equals_the_cli(dicesim, die1):
    d = dicesim.power(die1, against=dicesim.load_scene(FAIR), threads=2, **SMALL)
    cli = small_cli(DIE1, "--against", FAIR)
    assert d.keys() == cli.keys()
    for key in d:
        if key not in ("elapsed_s", "threads"):
            assert d[key] == cli[key], key
    assert d["mode"] == "against" and d["against"] == FAIR
    assert d["n_exact"] is not None and d["exact"]["power"] >= 0.8
    lo, hi = d["n_range95"]
    assert lo <= hi
    assert d["difference"]["significant"]


def test_power_detect_bias(dicesim):
    fair = dicesim.load_scene(FAIR)
    d = dicesim.power(fair, detect_bias=0.05, n=5000, replicates=500, bootstrap=100)
    assert d["mode"] == "detect_bias" and d["detect_bias"] == 0.05
    assert len(d["alternatives"]) == 12
    worst = max(a["n_exact"] for a in d["alternatives"])
    # The hardest was picked by its search and searched again on fresh replicates for n_exact.
    assert d["hardest"]["n_exact_selecting"] == worst and d["hardest"]["refreshed"]
    assert abs(d["n_exact"] - worst) < 0.2 * worst


def test_power_bad_input(dicesim, die1):
    fair = dicesim.load_scene(FAIR)
    with pytest.raises(ValueError, match="exactly one"):
        dicesim.power(die1)
    with pytest.raises(ValueError, match="exactly one"):
        dicesim.power(die1, against=fair, detect_bias=0.01)
    with pytest.raises(ValueError, match="alpha"):
        dicesim.power(die1, against=fair, alpha=1.5)
    with pytest.raises(ValueError, match="power"):
        dicesim.power(die1, against=fair, power=0.01)
    with pytest.raises(ValueError, match="detect_bias"):
        dicesim.power(die1, detect_bias=0.7)
    with pytest.raises(ValueError, match="n must be"):
        dicesim.power(die1, against=fair, n=10)
    with pytest.raises(dicesim.SceneError, match="outcome labels"):
        dicesim.power(die1, against=dicesim.load_scene("scenes/dice/d20.toml"), n=1000)
