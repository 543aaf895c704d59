"""The examples run (with few tosses) and write their PNG."""
import os
import subprocess
import sys

import pytest

from conftest import SOURCE_DIR, require


@pytest.mark.parametrize("script", ["sweep_aluminium.py", "single_toss.py", "fit_die1.py"])
def test_example_writes_png(script, tmp_path):
    require("matplotlib")
    out = tmp_path / (script[:-3] + ".png")
    env = {**os.environ, "MPLBACKEND": "Agg", "DICESIM_EXAMPLE_TOSSES": "200"}
    p = subprocess.run([sys.executable, str(SOURCE_DIR / "python/examples" / script), "--out", str(out)],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10000
