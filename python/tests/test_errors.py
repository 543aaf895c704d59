"""Bad input raises dicesim.SceneError (a ValueError) with the CLI's exit-2 message."""
import pytest

from conftest import DIE1, run_cli


def cli_error(*args):
    p = run_cli(*args, check=False)
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr.startswith("dicesim: error: ")
    return p.stderr[len("dicesim: error: "):].rstrip("\n")


@pytest.mark.parametrize("set_, cli_set", [
    ({"materials.steel.restitution": 3}, "materials.steel.restitution=3"),
    ({"foo.bar": 1}, "foo.bar=1"),
    ({"throw.height.mean": float("nan")}, "throw.height.mean=nan"),
    (["sim.stop_speed=-1"], "sim.stop_speed=-1"),
    ({"die.size": [0.03, 0.03]}, "die.size=[0.03, 0.03]"),
])
def test_bad_override_has_the_cli_message(dicesim, set_, cli_set):
    with pytest.raises(dicesim.SceneError) as e:
        dicesim.load_scene(DIE1, set=set_)
    assert isinstance(e.value, ValueError)
    assert str(e.value) == cli_error("toss", DIE1, "-n", "1", "--set", cli_set)
    assert e.value.file and e.value.key


def test_missing_file(dicesim):
    with pytest.raises(dicesim.SceneError) as e:
        dicesim.load_scene("scenes/no-such-scene.toml")
    assert str(e.value) == cli_error("toss", "scenes/no-such-scene.toml")


def test_bad_fidelity(dicesim, die1):
    with pytest.raises(dicesim.SceneError) as e:
        dicesim.toss(die1, 10, fidelity="bogus")
    # The CLI names its option (--fidelity), Python its argument (fidelity); the rest is the same.
    assert str(e.value).replace("fidelity: ", "--fidelity: ", 1) == cli_error("toss", DIE1, "--fidelity", "bogus")
    with pytest.raises(dicesim.SceneError):
        dicesim.toss_one(die1, 0, fidelity="bogus")


def test_bad_toml_text(dicesim):
    with pytest.raises(dicesim.SceneError) as e:
        dicesim.scene_from_toml("[die]\nsize = -1\n", name="inline")
    assert str(e.value).startswith("inline")


def test_bad_sweep_value_fails_before_tossing(dicesim, die1):
    with pytest.raises(dicesim.SceneError) as e:
        dicesim.sweep(die1, "materials.steel.restitution", [0.5, 2.0], 10**9)
    assert "materials.steel.restitution" in str(e.value)


def test_bad_arguments(dicesim, die1):
    with pytest.raises(ValueError):
        dicesim.toss(die1, 0)
    with pytest.raises(ValueError):
        dicesim.toss(die1, 10, threads=-1)
    with pytest.raises(ValueError):
        dicesim.toss(die1, 10, target_halfwidth=0.9)
    with pytest.raises(TypeError):
        dicesim.load_scene(DIE1, set={"throw.height.mean": object()})
