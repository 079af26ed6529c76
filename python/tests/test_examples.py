"""The scripts in examples/python run and write what they say (issue 26, item 6)."""

import os
import subprocess
import sys

import numpy as np
import pytest

import texgrad
from conftest import SOURCE, SPOT

EXAMPLES = SOURCE / "examples" / "python"


def run_example(name, *args):
    environment = dict(os.environ)
    # The child imports the same texgrad as this test (build tree or installed).
    package_root = os.path.dirname(os.path.dirname(texgrad.__file__))
    environment["PYTHONPATH"] = os.pathsep.join(
        filter(None, [package_root, environment.get("PYTHONPATH")]))
    result = subprocess.run([sys.executable, str(EXAMPLES / name), *map(str, args)],
                            capture_output=True, text=True, env=environment)
    assert result.returncode == 0, result.stderr
    return result.stdout


def test_geodesic_figure(tmp_path):
    if not SPOT.exists():
        pytest.skip("shared data missing")
    pytest.importorskip("matplotlib")
    out = tmp_path / "distance.png"
    stdout = run_example("geodesic_figure.py", SPOT, "--out", out, "--resolution", 128)
    assert "max distance" in stdout
    figure = texgrad.read_image(out)
    assert figure.shape[0] > 100 and figure.std() > 0  # a picture, not a blank page


def test_smooth_texture(tmp_path):
    out = tmp_path / "smoothed.png"
    stdout = run_example("smooth_texture.py", "--out", out, "--size", 128)
    assert "texel std" in stdout
    before, after = (float(x) for x in stdout.split("texel std ")[1].split(" -> "))
    assert after < before
    assert texgrad.read_image(out).dtype == np.uint8
