"""dicesim.show: the page `dicesim show` writes, displayable inline in Jupyter."""
import json
import os
import re

import pytest

from conftest import DIE1


def page_data(html):
    m = re.search(r'<script id="dicesim-data" type="application/json">(.*?)</script>', html, re.S)
    assert m, "no data in the page"
    return json.loads(m.group(1))


def test_show_die_is_one_self_contained_page(dicesim, die1):
    page = dicesim.show(die1)
    html = page.html
    assert html.startswith("<!DOCTYPE html>") and str(page) == html
    assert "<script src" not in html and "<link rel=\"stylesheet\"" not in html  # nothing loaded from elsewhere
    assert "THREE" in html  # three.js inlined
    d = page_data(html)
    assert "toss" not in d
    assert [f["label"] for f in d["die"]["faces"]] == [f["label"] for f in d["info"]["faces"]]
    assert d["die"]["kind"] == "polytope" and len(d["die"]["vertices"]) == 8
    # Jupyter: an iframe holding the page, escaped.
    r = page._repr_html_()
    assert r.startswith("<iframe srcdoc=\"&lt;!DOCTYPE html&gt;") and "<script" not in r


@pytest.mark.parametrize("fidelity", ["paper", "impulse"])
def test_show_toss_is_toss_one(dicesim, die1, fidelity):
    index = 77
    d = page_data(dicesim.show(die1, toss=index, seed=3, fidelity=fidelity).html)
    t = dicesim.toss_one(die1, index, seed=3, fidelity=fidelity)
    toss = d["toss"]
    assert toss["face"] == t["face"] and toss["status"] == t["status"] and toss["bounces"] == t["bounces"]
    assert toss["outcome"] == str(t["face"])
    assert [i["t"] for i in toss["impacts"]] == pytest.approx(list(t["impacts"]["t"]), rel=1e-6)
    assert [i["energy_after"] for i in toss["impacts"]] == pytest.approx(list(t["impacts"]["after"]["energy"]), rel=1e-5)
    assert all(i["kind"] in ("corner", "edge", "face") for i in toss["impacts"])
    frames = toss["frames"]
    times = [f[0] for f in frames]
    assert times == sorted(times) and times[0] == 0 and times[-1] == pytest.approx(t["t_end"], rel=1e-6)
    # Poses at the impacts are the trace's: the frame at the first contact has its COM.
    k = times.index(toss["impacts"][0]["t"])
    assert frames[k][1:4] == pytest.approx(list(t["impacts"]["before"]["position"][0]), abs=1e-7)
    # Nothing interpolated (sustained contact is the stepper's recorded states), and dense enough
    # to animate: no gap over 1 ms (flight sampled every 1 ms; steps kept at most 1 ms apart).
    assert toss["interpolated"] == []
    # (times are written to 7 significant digits: 1e-6 s of rounding at t ~ 1 s)
    assert max(b - a for a, b in zip(times, times[1:])) <= 1e-3 + 2e-6


def test_show_save(dicesim, die1, tmp_path):
    p = dicesim.show(die1)
    path = tmp_path / "die.html"
    p.save(str(path))
    assert path.read_text() == p.html
    with pytest.raises(ValueError):
        p.save(str(tmp_path / "no" / "such" / "dir.html"))
