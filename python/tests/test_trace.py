"""dicesim.toss_one: the very toss of a run, with its impacts as numpy arrays."""
import pytest

from conftest import require


def test_toss_one_is_toss_i_of_the_run(dicesim, die1):
    n = 300
    faces = [dicesim.toss_one(die1, i, seed=9, trace=False)["face"] for i in range(n)]
    r = dicesim.toss(die1, n, seed=9)
    assert [faces.count(label) for label in r.labels] == list(r.counts)


def test_trace_arrays_and_physics(dicesim, die1):
    np = require("numpy")
    t = dicesim.toss_one(die1, 77, seed=1)  # 9 impacts
    assert t["status"] == "settled" and t["face"] in die1.labels
    imp = t["impacts"]
    k = t["bounces"]
    assert k >= 1
    assert imp["t"].shape == (k,) and imp["bounce"].tolist() == list(range(1, k + 1))
    assert np.all(np.diff(imp["t"]) > 0) and imp["t"][-1] <= t["t_end"]
    for side in ("before", "after"):
        assert imp[side]["position"].shape == (k, 3) and imp[side]["R"].shape == (k, 3, 3)
    # Flight conserves energy: the energy at release equals the energy at the first contact...
    assert imp["before"]["energy"][0] == pytest.approx(t["initial_state"]["energy"], rel=1e-9)
    # ... and between one impact's rebound and the next contact.
    assert np.allclose(imp["after"]["energy"][:-1], imp["before"]["energy"][1:], rtol=1e-9)
    # Impacts with restitution < 1 only take energy away.
    assert np.all(imp["after"]["energy"] <= imp["before"]["energy"] + 1e-12)
    # The COM flies ballistically: the next contact's height from the rebound state.
    g = t["gravity"]
    dt = np.diff(imp["t"])
    z0, vz0 = imp["after"]["position"][:-1, 2], imp["after"]["velocity"][:-1, 2]
    assert np.allclose(z0 + vz0 * dt - 0.5 * g * dt**2, imp["before"]["position"][1:, 2], atol=1e-9)
    # The initial state is the drawn throw.
    assert t["initial"]["com_position"][2] == pytest.approx(t["initial_state"]["position"][2])


def test_trace_off(dicesim, die1):
    t = dicesim.toss_one(die1, 3, trace=False)
    assert t["impacts"] is None and t["bounces"] >= 1
