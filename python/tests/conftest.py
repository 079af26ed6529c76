"""Shared fixtures of the Python tests: the module from a build tree, the CLI, the shared meshes.

Environment: TEXGRAD_BUILD_DIR (default build/release under the source tree) holds the module
(python/texgrad) and the CLI (texgrad); TEXGRAD_SHARED_DATA the shared meshes (default
../shared/data next to the source tree). An installed module is used when the build tree has none.
"""

import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

SOURCE = pathlib.Path(__file__).resolve().parents[2]
BUILD = pathlib.Path(os.environ.get("TEXGRAD_BUILD_DIR", SOURCE / "build" / "release"))
if (BUILD / "python" / "texgrad").is_dir():
    sys.path.insert(0, str(BUILD / "python"))
SHARED = pathlib.Path(os.environ.get("TEXGRAD_SHARED_DATA", SOURCE.parent / "shared" / "data"))
SPOT = SHARED / "spot" / "spot_triangulated.obj"
SPOT_TEXTURE = SHARED / "spot" / "spot_texture.png"

import texgrad  # noqa: E402

# Texture size of most tests: small enough for the suite to take well under two minutes on two
# cores, large enough that spot's 13 charts cover thousands of texels each.
SIZE = 256


def cli():
    """Path of the texgrad program built next to the module."""
    path = BUILD / "texgrad"
    if not path.exists():
        pytest.skip(f"no texgrad program at {path} (TEXGRAD_BUILD_DIR)")
    return path


def run_cli(*args):
    """Runs the CLI quietly; raises with its stderr when it fails."""
    result = subprocess.run([str(cli()), *map(str, args)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    return result.stdout


@pytest.fixture(scope="session")
def spot_mesh():
    if not SPOT.exists():
        pytest.skip(f"shared data missing: {SPOT}")
    return texgrad.read_mesh(SPOT)


@pytest.fixture(scope="session")
def spot_domain(spot_mesh):
    return texgrad.TexelDomain(spot_mesh, SIZE, SIZE)


@pytest.fixture(scope="session")
def spot_texture_file(tmp_path_factory):
    """spot's texture box-filtered to SIZE x SIZE, as an 8-bit PNG both the CLI and tests read."""
    full = texgrad.read_image(SPOT_TEXTURE, dtype=np.float64)
    k = full.shape[0] // SIZE
    small = full.reshape(SIZE, k, SIZE, k, full.shape[2]).mean(axis=(1, 3))
    path = tmp_path_factory.mktemp("spot") / "texture.png"
    texgrad.write_image(path, small.astype(np.float32), bit_depth="8")
    return path
