"""Several dice among obstacles (docs/world.md) from Python: the CLI's counts, and one die's views refused."""
import pytest

from conftest import cli_json

CRAPS = "scenes/world/craps.toml"


def test_a_world_toss_counts_as_the_cli_does(dicesim):
    r = dicesim.toss(dicesim.load_scene(CRAPS), 60, seed=3, threads=2)
    cli = cli_json("toss", CRAPS, "-n", "60", "--seed", "3")
    assert list(r.labels) == list(range(2, 13))  # the sums of two d6
    assert list(r.counts) == [f["count"] for f in cli["faces"]]
    assert r.unresolved == cli["unresolved"]


def test_one_dies_views_refuse_a_world(dicesim):
    scene = dicesim.load_scene(CRAPS)
    with pytest.raises(ValueError, match="one die alone"):
        dicesim.toss_one(scene, 0, trace=True)
    with pytest.raises(ValueError, match="one die alone"):
        dicesim.show(scene, toss=0)
    assert dicesim.toss_one(scene, 0, trace=False)["status"] in ("settled", "unresolved")
