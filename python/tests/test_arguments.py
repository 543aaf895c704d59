"""Arguments as a newcomer writes them: a scene as a path, a count as 1e4, a mistyped fidelity."""
from pathlib import Path

import pytest

from conftest import DIE1, run_cli


def test_toss_takes_a_path_as_fit_does(dicesim, die1):
    by_path = dicesim.toss(DIE1, 200, seed=4)
    assert by_path.to_dict()["faces"] == dicesim.toss(die1, 200, seed=4).to_dict()["faces"]
    assert by_path.scene == DIE1
    assert dicesim.toss(Path(DIE1), 200, seed=4).counts.tolist() == by_path.counts.tolist()
    assert dicesim.sweep(DIE1, "floor.restitution", [0.3], 100).points[0].tosses == 100
    with pytest.raises(dicesim.SceneError):  # the file's own error, not a binding's TypeError
        dicesim.toss("scenes/no-such-scene.toml", 10)
    with pytest.raises(TypeError, match="scene must be a dicesim.Scene or a path"):
        dicesim.toss(42, 10)


def test_power_takes_paths_for_both_scenes(dicesim, die1):
    small = dict(n=2000, replicates=200, bootstrap=100, seed=3, threads=1)
    by_path = dicesim.power(DIE1, against=Path("scenes/fair.toml"), **small)
    by_scene = dicesim.power(die1, against=dicesim.load_scene("scenes/fair.toml"), **small)
    assert by_path["against"] == "scenes/fair.toml"
    for key in by_scene:
        if key not in ("elapsed_s",):
            assert by_path[key] == by_scene[key], key
    with pytest.raises(TypeError, match="scene must be a dicesim.Scene or a path"):
        dicesim.power(die1, against=6, **small)


def test_a_count_may_be_an_integral_float(dicesim, die1):
    assert dicesim.toss(die1, 1e3).tosses == 1000
    assert dicesim.toss(die1, 2.5e2, seed=2).counts.tolist() == dicesim.toss(die1, 250, seed=2).counts.tolist()
    assert len(dicesim.sweep(die1, "floor.restitution", [0.3, 0.5], 1e2)) == 2
    with pytest.raises(ValueError, match=r"n must be a whole number .*1\.5"):
        dicesim.toss(die1, 1.5)
    with pytest.raises(TypeError, match="n must be a whole number"):
        dicesim.toss(die1, "100")


def test_a_mistyped_fidelity_is_named_with_the_choices(dicesim, die1):
    with pytest.raises(dicesim.SceneError) as e:
        dicesim.toss(die1, 10, fidelity="impluse")
    msg = str(e.value)
    assert "'impluse'" in msg and "static, paper, impulse, stepped, auto" in msg
    assert "--set" not in msg and "sim.fidelity" not in msg
    p = run_cli("toss", DIE1, "-n", "10", "--fidelity", "impluse", check=False)
    assert p.returncode == 2 and p.stdout == ""
    assert "'impluse' is not a fidelity" in p.stderr and "--set" not in p.stderr
