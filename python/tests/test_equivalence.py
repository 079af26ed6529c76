"""The module's output equals the CLI's for the same options (same decode, same library calls).

Float outputs are compared through float EXR files (bit for bit); 8-bit outputs through PNG, also
bit for bit: the module quantises integer outputs with the rule image files use.
"""

import json

import numpy as np
import pytest

import texgrad
from conftest import SIZE, SPOT, run_cli


def exr(path):
    return texgrad.read_image(path, dtype=np.float32)


def test_filter_float_matches_cli(tmp_path, spot_mesh, spot_texture_file):
    out = tmp_path / "filtered.exr"
    run_cli("filter", SPOT, spot_texture_file, "--beta", "0.3", "--out", out,
            "--bit-depth", "float", "--quiet")
    image = texgrad.read_image(spot_texture_file, dtype=np.float32)
    result = texgrad.filter(spot_mesh, image, beta=0.3)
    assert result.dtype == np.float32
    assert np.array_equal(result, exr(out)[..., : result.shape[2]])


@pytest.mark.parametrize("beta", ["0", "3"])
def test_filter_raw_matches_cli_raw_and_bound_stays_in_range(tmp_path, spot_mesh,
                                                             spot_texture_file, beta):
    # raw=True is `--raw` (the exact solution at barely covered texels); the default clamps those
    # texels into the range of their input and their well-covered neighbours' solved values, so
    # where it differs from the raw solution the value lies within the input's and the other
    # texels' range.
    out = tmp_path / "raw.exr"
    run_cli("filter", SPOT, spot_texture_file, "--beta", beta, "--raw", "--out", out,
            "--bit-depth", "float", "--quiet")
    image = texgrad.read_image(spot_texture_file, dtype=np.float32)
    raw = texgrad.filter(spot_mesh, image, beta=float(beta), raw=True)
    assert np.array_equal(raw, exr(out)[..., : raw.shape[2]])
    bounded = texgrad.filter(spot_mesh, image, beta=float(beta))
    changed = np.any(bounded != raw, axis=2)
    assert changed.any()  # spot at this size has barely covered texels
    kept = bounded[~changed]
    low = np.minimum(image.min(axis=(0, 1)), kept.min(axis=0))
    high = np.maximum(image.max(axis=(0, 1)), kept.max(axis=0))
    assert np.any(raw[changed] < low) or np.any(raw[changed] > high)  # the raw values were not
    assert np.all(bounded[changed] >= low) and np.all(bounded[changed] <= high)


def test_filter_uint8_matches_cli_png(tmp_path, spot_mesh, spot_texture_file):
    out = tmp_path / "filtered.png"
    run_cli("filter", SPOT, spot_texture_file, "--beta", "2", "--out", out, "--quiet")
    image = texgrad.read_image(spot_texture_file)
    assert image.dtype == np.uint8
    result = texgrad.filter(spot_mesh, image, beta=2.0)
    assert result.dtype == np.uint8
    assert np.array_equal(result, texgrad.read_image(out))


def test_filter_beta_map_matches_cli(tmp_path, spot_mesh, spot_texture_file):
    ramp = np.tile(np.linspace(0, 1, 64, dtype=np.float32), (64, 1))
    texgrad.write_image(tmp_path / "beta.exr", ramp, bit_depth="float")
    out = tmp_path / "filtered.exr"
    run_cli("filter", SPOT, spot_texture_file, "--beta-map", tmp_path / "beta.exr",
            "--beta-range", "0", "3", "--out", out, "--bit-depth", "float", "--quiet")
    image = texgrad.read_image(spot_texture_file, dtype=np.float32)
    result = texgrad.filter(spot_mesh, image, beta_map=ramp, beta_range=(0, 3))
    assert np.array_equal(result, exr(out))


def test_seams_matches_cli(tmp_path, spot_mesh, spot_texture_file):
    out = tmp_path / "seams.exr"
    run_cli("seams", SPOT, spot_texture_file, "--out", out, "--bit-depth", "float", "--quiet")
    image = texgrad.read_image(spot_texture_file, dtype=np.float32)
    assert np.array_equal(texgrad.seams(spot_mesh, image), exr(out))


def test_dilate_matches_cli(tmp_path, spot_mesh, spot_texture_file):
    out = tmp_path / "dilated.exr"
    run_cli("dilate", SPOT, spot_texture_file, "--radius", "3", "--out", out,
            "--bit-depth", "float", "--quiet")
    image = texgrad.read_image(spot_texture_file, dtype=np.float32)
    assert np.array_equal(texgrad.dilate(spot_mesh, image, radius=3), exr(out))


def test_stitch_matches_cli(tmp_path, spot_mesh, spot_texture_file):
    image = texgrad.read_image(spot_texture_file, dtype=np.float32)
    segments = np.zeros((SIZE, SIZE, 3), np.uint8)
    segments[:, : SIZE // 2] = (255, 0, 0)
    segments[:, SIZE // 2:] = (0, 255, 0)
    composite = image.copy()
    composite[:, SIZE // 2:] *= 0.7  # the second source is darker
    texgrad.write_image(tmp_path / "composite.exr", composite, bit_depth="float")
    texgrad.write_image(tmp_path / "segments.png", segments)
    out = tmp_path / "stitched.exr"
    run_cli("stitch", SPOT, "--composite", tmp_path / "composite.exr", "--segments",
            tmp_path / "segments.png", "--out", out, "--bit-depth", "float", "--quiet")
    result = texgrad.stitch(spot_mesh, composite=composite, segments=segments)
    assert np.array_equal(result, exr(out))


def test_geodesic_matches_cli(tmp_path, spot_mesh):
    out = tmp_path / "distance.exr"
    run_cli("geodesic", SPOT, "--source-vertex", "100", "--resolution", SIZE, "--out", out,
            "--quiet")
    result = texgrad.geodesic(spot_mesh, source_vertices=[100], resolution=SIZE)
    assert result.shape == (SIZE, SIZE)
    assert np.array_equal(result, exr(out)[..., 0])


def test_lic_matches_cli(tmp_path, spot_mesh):
    out = tmp_path / "lic.exr"
    run_cli("lic", SPOT, "--resolution", 128, "--out", out, "--bit-depth", "float", "--quiet")
    assert np.array_equal(texgrad.lic(spot_mesh, 128), exr(out)[..., 0])


def test_react_matches_cli(tmp_path, spot_mesh):
    out = tmp_path / "react.exr"
    run_cli("react", SPOT, "--resolution", 128, "--steps", 40, "--out", out,
            "--bit-depth", "float", "--quiet")
    assert np.array_equal(texgrad.react(spot_mesh, 128, steps=40), exr(out)[..., 0])


@pytest.mark.parametrize("kind", ["active", "chart"])
def test_mask_matches_cli(tmp_path, spot_mesh, kind):
    out = tmp_path / "mask.png"
    run_cli("mask", SPOT, "--resolution", SIZE, "--kind", kind, "--out", out, "--quiet")
    assert np.array_equal(texgrad.mask(spot_mesh, SIZE, kind=kind), texgrad.read_image(out))


def test_atlas_report_matches_info_json(spot_mesh):
    expected = json.loads(run_cli("info", SPOT, "--resolution", SIZE, "--json"))
    report = spot_mesh.atlas_report(SIZE)
    expected.pop("mesh")
    assert report.pop("mesh") == str(SPOT)
    assert {t["slot"]: t["file"] for t in report["textures"]} == spot_mesh.textures
    assert report["missing_files"] == []
    assert report == expected


def test_atlas_report_of_udim_tiles_matches_info_json(tmp_path):
    # Two triangles in UDIM tiles 1001 and 1002: read_mesh keeps them in their tiles (the CLI's
    # pages), so both list two pages, and no UV is outside its tile.
    (tmp_path / "t.mtl").write_text("newmtl m\nmap_Kd t.<UDIM>.png\n")
    (tmp_path / "t.obj").write_text(
        "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
        "vt 0.2 0.2\nvt 0.8 0.2\nvt 0.2 0.8\nvt 1.2 0.2\nvt 1.8 0.2\nvt 1.2 0.8\n"
        "usemtl m\nf 1/1 2/2 3/3\nf 1/4 2/5 4/6\n")
    for tile in ("1001", "1002"):
        texgrad.write_image(tmp_path / f"t.{tile}.png", np.zeros((8, 8, 3), np.uint8))
    expected = json.loads(run_cli("info", tmp_path / "t.obj", "--json"))
    report = texgrad.read_mesh(tmp_path / "t.obj").atlas_report()
    assert [p["name"] for p in report["pages"]["baseColor"]["pages"]] == ["1001", "1002"]
    assert all(i["kind"] != "uvs-outside-unit-square" for i in report["issues"])
    expected.pop("mesh")
    report.pop("mesh")
    assert report == expected


def test_mask_and_dilate_on_a_domain_equal_those_on_its_mesh(spot_mesh, spot_domain,
                                                             spot_texture_file):
    # A TexelDomain lends its own grid; a Mesh gets one built at the image's size.
    image = texgrad.read_image(spot_texture_file, dtype=np.float32)
    assert np.array_equal(texgrad.dilate(spot_domain, image, radius=3),
                          texgrad.dilate(spot_mesh, image, radius=3))
    assert np.array_equal(texgrad.mask(spot_domain, kind="chart"),
                          texgrad.mask(spot_mesh, SIZE, kind="chart"))


def test_wrapped_mesh_filters_like_its_copy_in_the_image(tmp_path, spot_mesh, spot_texture_file):
    # spot with its UVs moved by one tile in v: read_mesh wraps it (OBJ: repeat) as the CLI does,
    # so the filter's output is spot's own (to 1e-6: v + 1 - 1 rounds); wrap="clamp" keeps the
    # file's UVs, which then lie outside the image and are refused.
    lines = SPOT.read_text().splitlines()
    moved = [f"vt {float(l.split()[1]):.17g} {float(l.split()[2]) + 1:.17g}"
             if l.startswith("vt ") else l for l in lines if not l.startswith("mtllib")]
    up = tmp_path / "spot_up.obj"
    up.write_text("\n".join(moved) + "\n")
    image = texgrad.read_image(spot_texture_file, dtype=np.float32)
    expected = texgrad.filter(spot_mesh, image, beta=0.3)
    assert np.abs(texgrad.filter(texgrad.read_mesh(up), image, beta=0.3) - expected).max() < 1e-6
    with pytest.raises(ValueError, match="outside the image"):
        texgrad.filter(texgrad.read_mesh(up, wrap="clamp"), image, beta=0.3)
    mesh, parents = texgrad.read_mesh(up, wrap="clamp").wrapped("repeat")
    assert parents.dtype == np.int32 and parents.shape == (mesh.face_count,)
    assert parents.min() == 0 and parents.max() == spot_mesh_face_count(up) - 1
    assert np.abs(texgrad.filter(mesh, image, beta=0.3) - expected).max() < 1e-6


def spot_mesh_face_count(path):
    return sum(1 for line in path.read_text().splitlines() if line.startswith("f "))
