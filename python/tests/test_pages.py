"""Texture pages from Python: a UDIM asset read over its tiles, filtered on the layout and written
per tile equals the CLI's per-tile output; the layout, its split and its file names; errors."""

import numpy as np
import pytest

import texgrad
from conftest import run_cli

TILES = ["1001", "1002", "1011", "1012"]
TILE_SIZE = 64


def cube_over_tiles(folder, grid=6):
    """A cube whose six sides are six charts spread over UDIM tiles 1001, 1002, 1011 and 1012
    (side i in tile i % 2, (i // 2) % 2), written as tiles.obj + tiles.mtl (map_Kd
    t.<UDIM>.png) with a smooth random 64 x 64 8-bit image per tile. Cube edges are seams
    between charts of different tiles."""
    vertices, uvs, faces = [], [], []
    for side in range(6):
        axis, sign = side // 2, (1.0, -1.0)[side % 2]
        b, c = (axis + 1) % 3, (axis + 2) % 3
        origin = np.array([0.05 + 0.5 * (side // 4) + side % 2, 0.3 + (side // 2) % 2])
        first = len(vertices)
        for j in range(grid + 1):
            for i in range(grid + 1):
                p = [0.0, 0.0, 0.0]
                p[axis], p[b], p[c] = sign, -1 + 2 * i / grid, -1 + 2 * j / grid
                vertices.append(p)
                s = i / grid if sign > 0 else 1 - i / grid  # UVs counter-clockwise outside
                uvs.append(origin + 0.4 * np.array([s, j / grid]))
        for j in range(grid):
            for i in range(grid):
                k = first + j * (grid + 1) + i
                quad = [(k, k + 1, k + grid + 2), (k, k + grid + 2, k + grid + 1)]
                faces += quad if sign > 0 else [t[::-1] for t in quad]
    (folder / "tiles.mtl").write_text("newmtl m\nmap_Kd t.<UDIM>.png\n")
    lines = ["mtllib tiles.mtl"]
    lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices]
    lines += [f"vt {u!r} {v!r}" for u, v in uvs]
    lines += ["usemtl m"] + [f"f {a + 1}/{a + 1} {b + 1}/{b + 1} {c + 1}/{c + 1}"
                             for a, b, c in faces]
    (folder / "tiles.obj").write_text("\n".join(lines) + "\n")
    rng = np.random.default_rng(30)
    for tile in TILES:
        coarse = rng.random((8, 8, 3))
        image = np.kron(coarse, np.ones((8, 8, 1)))  # 8 x 8 blocks: edges for the filter
        texgrad.write_image(folder / f"t.{tile}.png", image.astype(np.float32), bit_depth="8")
    return folder / "tiles.obj"


@pytest.mark.parametrize("suffix, dtype, bit_depth", [
    ("exr", np.float32, "float"),  # float outputs: bit for bit
    ("png", None, None),  # the files' uint8, written as the CLI writes PNG by default
])
def test_filter_over_udim_tiles_matches_cli_per_tile(tmp_path, suffix, dtype, bit_depth):
    obj = cube_over_tiles(tmp_path)
    cli_args = ["filter", obj, "--beta", "0.3", "--out", tmp_path / f"cli.<UDIM>.{suffix}", "-q"]
    run_cli(*cli_args, *(["--bit-depth", bit_depth] if bit_depth else []))

    pages = texgrad.read_texture_pages(texgrad.read_mesh(obj), dtype=dtype)
    layout = pages.layout
    assert layout.udim and [p["name"] for p in layout.pages] == TILES
    assert pages.image.shape[:2] == (layout.height, layout.width)
    assert pages.image.dtype == (dtype or np.uint8)
    result = texgrad.filter(pages.mesh, pages.image, beta=0.3)
    assert result.dtype == pages.image.dtype
    written = texgrad.write_texture_pages(tmp_path / f"py.<UDIM>.{suffix}", layout, result,
                                          bit_depth=bit_depth)
    assert written == [str(tmp_path / f"py.{tile}.{suffix}") for tile in TILES]
    assert written == layout.output_paths(tmp_path / f"py.<UDIM>.{suffix}")
    split = layout.split(result)
    for tile in TILES:
        expected = texgrad.read_image(tmp_path / f"cli.{tile}.{suffix}", dtype=dtype)
        expected = expected[..., : result.shape[2]]
        assert np.array_equal(texgrad.read_image(written[TILES.index(tile)], dtype=dtype)
                              [..., : result.shape[2]], expected), tile
        assert np.array_equal(split[tile], expected), tile
        source = texgrad.read_image(tmp_path / f"t.{tile}.png", dtype=dtype)
        assert np.count_nonzero(np.any(split[tile] != source, axis=2)) > 100, tile  # filtered


def test_layout_places_each_tile_at_its_offset(tmp_path):
    pages = texgrad.read_texture_pages(texgrad.read_mesh(cube_over_tiles(tmp_path)))
    offsets = [p["offset"] for p in pages.layout.pages]
    assert offsets[0] == 0 and all(o % 64 == 0 for o in offsets)
    assert all(b - a >= TILE_SIZE + 8 for a, b in zip(offsets, offsets[1:]))
    assert [p["tile"] for p in pages.layout.pages] == [(0, 0), (1, 0), (0, 1), (1, 1)]
    assert all(p["file"].endswith(f"t.{t}.png") for p, t in zip(pages.layout.pages, TILES))
    for page, (name, image) in zip(pages.layout.pages, pages.layout.split(pages.image).items()):
        assert name == page["name"]
        assert np.array_equal(image, texgrad.read_image(page["file"]))
        # The layout image holds the page at its offset, rows from the bottom (row 0 = top).
        assert np.array_equal(pages.image[pages.layout.height - TILE_SIZE:,
                                          page["offset"]:page["offset"] + TILE_SIZE], image)
    uvs = pages.mesh.uvs
    assert uvs.min() >= 0 and uvs.max() <= 1  # in the layout's UV space
    planar = pages.layout.split(pages.image[..., 0], dtype=np.float32)["1002"]
    assert planar.shape == (TILE_SIZE, TILE_SIZE) and planar.dtype == np.float32


def test_udim_tiles_named_by_texture_argument_match_cli(tmp_path):
    # An OBJ naming no texture: the tiles come from texture= as from the CLI's TEXTURE argument;
    # read_mesh(texture=) keeps the faces in their tiles (wrapping would fold them into one).
    obj = cube_over_tiles(tmp_path)
    (tmp_path / "bare.obj").write_text(
        "".join(line for line in obj.read_text().splitlines(True)
                if not line.startswith(("mtllib", "usemtl"))))
    tiles = tmp_path / "t.<UDIM>.png"
    run_cli("filter", tmp_path / "bare.obj", tiles, "--beta", "0.3", "--out",
            tmp_path / "cli.<UDIM>.png", "-q")
    mesh = texgrad.read_mesh(tmp_path / "bare.obj", texture=tiles)
    pages = texgrad.read_texture_pages(mesh, texture=tiles)
    assert [p["name"] for p in pages.layout.pages] == TILES
    named = texgrad.read_texture_pages(texgrad.read_mesh(obj))
    assert np.array_equal(pages.image, named.image)
    written = texgrad.write_texture_pages(tmp_path / "py.<UDIM>.png", pages.layout,
                                          texgrad.filter(pages.mesh, pages.image, beta=0.3))
    for tile, path in zip(TILES, written):
        assert np.array_equal(texgrad.read_image(path),
                              texgrad.read_image(tmp_path / f"cli.{tile}.png")), tile
    wrapped, parents = texgrad.read_mesh(tmp_path / "bare.obj", wrap="clamp").wrapped(
        texture=tiles)
    assert np.array_equal(wrapped.uvs, mesh.uvs) and len(parents) == wrapped.face_count

def test_geodesic_over_udim_tiles_matches_cli_per_tile(tmp_path):
    # place_on_pages without images read: the tiles' sizes from their headers, as the CLI's
    # geodesic takes them; distances over the layout cross the tile borders by the seams.
    obj = cube_over_tiles(tmp_path)
    run_cli("geodesic", obj, "--source-vertex", "0", "--out", tmp_path / "cli.<UDIM>.exr", "-q")
    mesh, layout = texgrad.place_on_pages(texgrad.read_mesh(obj))
    assert (layout.width, layout.height) == (448, TILE_SIZE)
    distance = texgrad.geodesic(mesh, source_vertices=[0],
                                resolution=(layout.width, layout.height))
    written = texgrad.write_texture_pages(tmp_path / "py.<UDIM>.exr", layout, distance,
                                          bit_depth="float")
    for tile, path in zip(TILES, written):
        ours = texgrad.read_image(path)
        assert np.array_equal(ours, texgrad.read_image(tmp_path / f"cli.{tile}.exr")), tile
        assert ours.max() > 1.0, tile  # every tile reached (the cube's side is 2)
    _, sized = texgrad.place_on_pages(texgrad.read_mesh(obj), 32)
    assert [(p["width"], p["height"]) for p in sized.pages] == [(32, 32)] * 4

def test_missing_tile_raises_naming_its_file(tmp_path):
    obj = cube_over_tiles(tmp_path)
    (tmp_path / "t.1012.png").unlink()
    with pytest.raises(texgrad.IoError, match=r"t\.1012\.png"):
        texgrad.read_texture_pages(texgrad.read_mesh(obj))


def test_write_texture_pages_refuses_wrong_sizes_and_udim_gltf(tmp_path):
    pages = texgrad.read_texture_pages(texgrad.read_mesh(cube_over_tiles(tmp_path)))
    with pytest.raises(texgrad.InvalidInputError, match=r"image is 63 x 448 \(H x W\)"):
        texgrad.write_texture_pages(tmp_path / "o.<UDIM>.png", pages.layout, pages.image[1:])
    with pytest.raises(texgrad.InvalidInputError, match="layout"):
        pages.layout.split(pages.image[:, 1:])
    with pytest.raises(texgrad.InvalidInputError):  # an OBJ has no glTF asset to copy
        texgrad.write_texture_pages(tmp_path / "o.glb", pages.layout, pages.image)
    assert not list(tmp_path.glob("o.*"))


def test_one_page_is_the_mesh_and_its_texture(spot_mesh):
    pages = texgrad.read_texture_pages(spot_mesh, dtype=np.float32)
    assert pages.mesh is spot_mesh
    assert len(pages.layout) == 1 and not pages.layout.udim
    assert np.array_equal(pages.image, spot_mesh.texture(dtype=np.float32))
    assert pages.layout.output_paths("out.png") == ["out.png"]


def two_material_gltf(folder, grid=4):
    """Two square patches meeting at a right angle along an edge (a seam between two pages),
    each a material with its own base-colour image a.png / b.png (48 x 48 8-bit), as two.gltf
    with its buffer embedded."""
    import base64
    import json

    primitives, accessors, views, blob = [], [], [], bytearray()

    def add(array, target, kind, with_bounds=False):
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": array.nbytes,
                      "target": target})
        blob.extend(array.tobytes())
        blob.extend(b"\0" * (-len(blob) % 4))
        accessor = {"bufferView": len(views) - 1, "count": len(array), "type": kind,
                    "componentType": 5125 if array.dtype == np.uint32 else 5126}
        if with_bounds:
            accessor.update(min=array.min(axis=0).tolist(), max=array.max(axis=0).tolist())
        accessors.append(accessor)
        return len(accessors) - 1

    steps = np.linspace(0.0, 1.0, grid + 1)
    for side in range(2):
        s, t = np.meshgrid(steps, steps)
        if side == 0:  # the patch y = 0, z in [0, 1]; the other x = 0: they share the z axis
            p = np.stack([s, np.zeros_like(s), t], axis=-1)
        else:
            p = np.stack([np.zeros_like(s), 1 - s, t], axis=-1)
        uv = np.stack([0.1 + 0.8 * s, 1 - (0.1 + 0.8 * t)], axis=-1)  # glTF v points down
        k = np.arange((grid + 1) ** 2).reshape(grid + 1, grid + 1)[:-1, :-1].ravel()
        tris = np.concatenate([np.stack([k, k + 1, k + grid + 2], 1),
                               np.stack([k, k + grid + 2, k + grid + 1], 1)])
        primitives.append({
            "attributes": {
                "POSITION": add(p.reshape(-1, 3).astype(np.float32), 34962, "VEC3", True),
                "TEXCOORD_0": add(uv.reshape(-1, 2).astype(np.float32), 34962, "VEC2")},
            "indices": add(tris.astype(np.uint32).ravel(), 34963, "SCALAR"),
            "material": side})
    rng = np.random.default_rng(31)
    for name in ("a", "b"):
        image = np.kron(rng.random((6, 6, 3)), np.ones((8, 8, 1))).astype(np.float32)
        texgrad.write_image(folder / f"{name}.png", image, bit_depth="8")
    gltf = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}], "meshes": [{"primitives": primitives}],
        "materials": [{"name": n, "pbrMetallicRoughness": {"baseColorTexture": {"index": i}}}
                      for i, n in enumerate(("ma", "mb"))],
        "textures": [{"source": 0}, {"source": 1}],
        "images": [{"uri": "a.png"}, {"uri": "b.png"}],
        "accessors": accessors, "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(bytes(blob)).decode()}]}
    (folder / "two.gltf").write_text(json.dumps(gltf))
    return folder / "two.gltf"


def test_filter_of_two_material_gltf_matches_cli_glb_and_image_pages(tmp_path):
    gltf = two_material_gltf(tmp_path)
    run_cli("filter", gltf, "--beta", "0.3", "--out", tmp_path / "cli.glb", "-q")
    run_cli("filter", gltf, "--beta", "0.3", "--out", tmp_path / "cli.png", "-q")
    pages = texgrad.read_texture_pages(texgrad.read_mesh(gltf))
    assert len(pages.layout) == 2 and not pages.layout.udim
    result = texgrad.filter(pages.mesh, pages.image, beta=0.3)
    assert texgrad.write_texture_pages(tmp_path / "py.glb", pages.layout, result) == \
        [str(tmp_path / "py.glb")]
    names = [p["name"] for p in pages.layout.pages]
    written = texgrad.write_texture_pages(tmp_path / "py.png", pages.layout, result)
    assert written == [str(tmp_path / f"py.{name}.png") for name in names]
    split = pages.layout.split(result)
    for name, path in zip(names, written):
        assert np.array_equal(texgrad.read_image(path), texgrad.read_image(
            tmp_path / f"cli.{name}.png")), name
        assert np.count_nonzero(split[name] != texgrad.read_image(
            pages.layout.pages[names.index(name)]["file"])) > 100, name  # filtered
    # Each image of the glTF copy is its page's (the images keep their order in the copy).
    ours = texgrad.read_texture_pages(texgrad.read_mesh(tmp_path / "py.glb"))
    theirs = texgrad.read_texture_pages(texgrad.read_mesh(tmp_path / "cli.glb"))
    assert np.array_equal(ours.image, theirs.image)
    for name, page in zip(names, ours.layout.split(ours.image).values()):
        assert np.array_equal(page, split[name][..., : page.shape[2]]), name
