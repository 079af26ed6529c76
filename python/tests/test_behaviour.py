"""What users rely on: bad input raises a Python exception naming the argument (never a crash),
any dtype and memory order, progress callbacks, Ctrl-C, and the GIL released during solves."""

import base64
import io
import json
import os
import signal
import threading
import time

import numpy as np
import pytest

import texgrad
from conftest import SIZE

SQUARE_VERTICES = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
SQUARE_FACES = np.array([[0, 1, 2], [0, 2, 3]])
SQUARE_UVS = np.array([[0.1, 0.1], [0.9, 0.1], [0.9, 0.9], [0.1, 0.9]])


@pytest.fixture(scope="module")
def square():
    return texgrad.Mesh(SQUARE_VERTICES, SQUARE_FACES, SQUARE_UVS)


@pytest.fixture(scope="module")
def square_domain(square):
    return texgrad.TexelDomain(square, 32, 32)


def grey(shape=(32, 32, 3), dtype=np.float32):
    return np.full(shape, 0.5, dtype)


def with_nan():
    image = grey()
    image[3, 4, 1] = np.nan
    return image


def read_only():
    image = grey()
    image.flags.writeable = False
    return image


def obj_without_uvs(tmp_path):
    path = tmp_path / "no_uvs.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    return path


# (call, exception, words the message must contain): each call gets (square, domain, tmp_path).
BAD_INPUTS = {
    "image 1-D": (lambda m, d, t: texgrad.filter(d, np.zeros(32)), ValueError, "image"),
    "image 5 channels": (lambda m, d, t: texgrad.filter(d, grey((32, 32, 5))), ValueError,
                         "image"),
    "image NaN": (lambda m, d, t: texgrad.filter(d, with_nan()), ValueError, "image"),
    "image empty": (lambda m, d, t: texgrad.filter(m, grey((0, 0, 3))), ValueError, "image"),
    "image int64": (lambda m, d, t: texgrad.filter(d, grey(dtype=np.int64)), TypeError, "image"),
    "image complex": (lambda m, d, t: texgrad.filter(d, grey(dtype=np.complex64)), TypeError,
                      "image"),
    "image None": (lambda m, d, t: texgrad.filter(d, None), TypeError, "image"),
    "image wrong size": (lambda m, d, t: texgrad.filter(d, grey((16, 32, 3))), ValueError,
                         "image"),
    "image read-only scatter": (lambda m, d, t: d.scatter(np.zeros((d.unknowns, 3)), read_only()),
                                ValueError, "image"),
    "values wrong shape": (lambda m, d, t: d.scatter(np.zeros((3, 3)), grey()), ValueError,
                           "values"),
    "values NaN": (lambda m, d, t: d.scatter(np.full((d.unknowns, 3), np.nan), grey()),
                   ValueError, "values"),
    "faces out of range": (lambda m, d, t: texgrad.Mesh(SQUARE_VERTICES, [[0, 1, 9]], SQUARE_UVS),
                           ValueError, "faces"),
    "faces negative": (lambda m, d, t: texgrad.Mesh(SQUARE_VERTICES, [[0, -1, 2]], SQUARE_UVS),
                       ValueError, "faces"),
    "faces float": (lambda m, d, t: texgrad.Mesh(SQUARE_VERTICES, SQUARE_FACES * 1.0, SQUARE_UVS),
                    TypeError, "faces"),
    "faces empty": (lambda m, d, t: texgrad.Mesh(SQUARE_VERTICES, np.zeros((0, 3), int),
                                                 SQUARE_UVS), ValueError, "faces"),
    "uv_faces out of range": (lambda m, d, t: texgrad.Mesh(SQUARE_VERTICES, SQUARE_FACES,
                                                           SQUARE_UVS, [[0, 1, 2], [0, 2, 7]]),
                              ValueError, "uv_faces"),
    "uv_faces rows": (lambda m, d, t: texgrad.Mesh(SQUARE_VERTICES, SQUARE_FACES, SQUARE_UVS,
                                                   [[0, 1, 2]]), ValueError, "uv_faces"),
    "vertices 2-D points": (lambda m, d, t: texgrad.Mesh(SQUARE_VERTICES[:, :2], SQUARE_FACES,
                                                         SQUARE_UVS), ValueError, "vertices"),
    "vertices NaN": (lambda m, d, t: texgrad.Mesh(SQUARE_VERTICES * np.nan, SQUARE_FACES,
                                                  SQUARE_UVS), ValueError, "vertices"),
    "vertices empty": (lambda m, d, t: texgrad.Mesh(np.zeros((0, 3)), SQUARE_FACES, SQUARE_UVS),
                       ValueError, "vertices"),
    "mesh without uvs": (lambda m, d, t: texgrad.Mesh(SQUARE_VERTICES, SQUARE_FACES, None),
                         ValueError, "uvs"),
    "per-vertex uvs count": (lambda m, d, t: texgrad.Mesh(SQUARE_VERTICES, SQUARE_FACES,
                                                          SQUARE_UVS[:3]), ValueError, "uvs"),
    "obj without uvs": (lambda m, d, t: texgrad.read_mesh(obj_without_uvs(t)), ValueError,
                        "no_uvs.obj"),
    "missing file": (lambda m, d, t: texgrad.read_mesh(t / "missing.obj"), OSError,
                     "missing.obj"),
    "mesh not a mesh": (lambda m, d, t: texgrad.filter("spot.obj", grey()), TypeError, "mesh"),
    "domain size": (lambda m, d, t: texgrad.TexelDomain(m, 0, 32), ValueError, "width"),
    "alpha negative": (lambda m, d, t: texgrad.filter(d, grey(), alpha=-1.0), ValueError,
                       "alpha"),
    "beta NaN": (lambda m, d, t: texgrad.filter(d, grey(), beta=float("nan")), ValueError,
                 "beta"),
    "beta_map NaN": (lambda m, d, t: texgrad.filter(d, grey(), beta_map=with_nan()), ValueError,
                     "beta_map"),
    "solver name": (lambda m, d, t: texgrad.filter(d, grey(), solver="magic"), ValueError,
                    "solver"),
    "cycles type": (lambda m, d, t: texgrad.filter(d, grey(), cycles="many"), TypeError,
                    "cycles"),
    "cycles range": (lambda m, d, t: texgrad.filter(d, grey(), solver="multigrid", cycles=0),
                     ValueError, "cycles"),
    "unknown keyword": (lambda m, d, t: texgrad.filter(d, grey(), colour=True), TypeError,
                        "colour"),
    "output dtype": (lambda m, d, t: texgrad.filter(d, grey(), dtype=np.int32), TypeError,
                     "dtype"),
    "source vertex range": (lambda m, d, t: texgrad.geodesic(d, source_vertices=[99]),
                            ValueError, "source_vertices"),
    "source uvs shape": (lambda m, d, t: texgrad.geodesic(d, source_uvs=[0.5, 0.5, 0.5]),
                         ValueError, "source_uvs"),
    "no source": (lambda m, d, t: texgrad.geodesic(d), ValueError, "source"),
    "segments missing": (lambda m, d, t: texgrad.stitch(d, composite=grey()), ValueError,
                         "segments"),
    "partials empty": (lambda m, d, t: texgrad.stitch(d, partials=[], confidences=[]),
                       ValueError, "partials"),
    "lic field shape": (lambda m, d, t: texgrad.lic(d, field=np.ones((5, 3))), ValueError,
                        "field"),
    "react steps": (lambda m, d, t: texgrad.react(d, steps=-1), ValueError, "steps"),
    "mask kind": (lambda m, d, t: texgrad.mask(d, kind="charts"), ValueError, "charts"),
    "dilate radius": (lambda m, d, t: texgrad.dilate(d, grey(), radius=-2), ValueError,
                      "radius"),
    "uvs outside image": (lambda m, d, t: texgrad.TexelDomain(
        texgrad.Mesh(SQUARE_VERTICES, SQUARE_FACES, SQUARE_UVS + 5.0), 32, 32), ValueError,
        "UV"),
}


@pytest.mark.parametrize("case", sorted(BAD_INPUTS))
def test_bad_input_raises_a_python_exception_naming_it(case, square, square_domain, tmp_path):
    call, exception, words = BAD_INPUTS[case]
    with pytest.raises(exception) as raised:
        call(square, square_domain, tmp_path)
    assert words in str(raised.value), str(raised.value)


def test_errors_have_the_builtin_bases():
    assert issubclass(texgrad.InvalidInputError, ValueError)
    assert issubclass(texgrad.IoError, OSError)
    assert issubclass(texgrad.NumericalError, RuntimeError)
    assert issubclass(texgrad.UnsupportedError, ValueError)
    assert issubclass(texgrad.UnsupportedError, NotImplementedError)


def test_any_memory_order_and_read_only_inputs_give_the_same_result(square_domain):
    rng = np.random.default_rng(1)
    image = rng.random((32, 32, 3), dtype=np.float32)
    expected = texgrad.filter(square_domain, image, beta=0.5)
    fortran = np.asfortranarray(image)
    strided = np.zeros((32, 64, 6), np.float32)[:, ::2, ::2]
    strided[...] = image
    flipped = image[::-1][::-1]  # negative strides
    frozen = image.copy()
    frozen.flags.writeable = False
    for variant in (fortran, strided, flipped, frozen):
        assert np.array_equal(texgrad.filter(square_domain, variant, beta=0.5), expected)


def test_output_dtype_follows_the_input(square_domain):
    for dtype in (np.uint8, np.uint16, np.float32, np.float64):
        image = (grey() * np.iinfo(dtype).max).astype(dtype) if dtype in (
            np.uint8, np.uint16) else grey(dtype=dtype)
        assert texgrad.filter(square_domain, image, beta=0.5).dtype == dtype
    planar = texgrad.filter(square_domain, grey((32, 32)), beta=0.5)
    assert planar.shape == (32, 32)
    assert texgrad.filter(square_domain, grey(), beta=0.5, dtype=np.uint16).dtype == np.uint16


def test_progress_callback_sees_stages_and_can_cancel(spot_mesh):
    seen = []
    texgrad.react(spot_mesh, 64, steps=20, progress=lambda stage, f: seen.append((stage, f)))
    assert ("react", 1.0) in seen
    assert all(0.0 <= f <= 1.0 for _, f in seen)
    with pytest.raises(texgrad.Cancelled):
        texgrad.react(spot_mesh, 64, steps=20, progress=lambda stage, f: f < 0.5)

    def fails(stage, fraction):
        raise ZeroDivisionError("from the callback")

    with pytest.raises(ZeroDivisionError, match="from the callback"):
        texgrad.react(spot_mesh, 64, steps=20, progress=fails)


def interrupt_after(seconds):
    """Sends SIGINT to this process from another thread after `seconds`; returns the thread."""
    def send():
        time.sleep(seconds)
        os.kill(os.getpid(), signal.SIGINT)

    thread = threading.Thread(target=send)
    thread.start()
    return thread


@pytest.mark.parametrize("app", ["filter", "geodesic", "react"])
def test_ctrl_c_interrupts_a_long_solve_within_a_second(spot_domain, app):
    image = np.random.default_rng(1).random((SIZE, SIZE, 3), dtype=np.float32)
    # Each call would run for minutes (10^5 V-cycles with no tolerance to stop at, about 15 ms
    # each; 10^5 time steps); SIGINT comes after 0.5 s.
    long_calls = {
        "filter": lambda: texgrad.filter(spot_domain, image, beta=0.5, solver="multigrid",
                                         cycles=100000, tolerance=0.0),
        "geodesic": lambda: texgrad.geodesic(spot_domain, source_vertices=[0],
                                             solver="multigrid", cycles=100000, tolerance=0.0),
        "react": lambda: texgrad.react(spot_domain, steps=100000),
    }
    thread = interrupt_after(0.5)
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        long_calls[app]()
    elapsed = time.monotonic() - start
    thread.join()
    assert elapsed < 0.5 + 1.0
    # The module stays usable: the same domain solves again, as a fresh solve does.
    again = texgrad.filter(spot_domain, image, beta=0.5, solver="direct")
    assert np.array_equal(again, texgrad.filter(spot_domain, image, beta=0.5, solver="direct"))


def test_interactive_solvers_take_progress_and_ctrl_c(spot_domain, spot_texture_file):
    image = texgrad.read_image(spot_texture_file, dtype=np.float32)
    stages = []
    interactive = texgrad.InteractiveFilter(
        spot_domain, image, beta=0.0, solver="multigrid", cycles=100000, tolerance=0.0,
        progress=lambda stage, fraction: stages.append(stage))
    assert "solver setup" in stages
    thread = interrupt_after(0.5)
    with pytest.raises(KeyboardInterrupt):
        interactive.solve()
    thread.join()
    # Still usable after the interrupt: 0.5 s of cycles converged, and a few more steps give what
    # a fresh direct filter gives.
    for _ in range(3):
        interactive.step()
    fresh = texgrad.filter(spot_domain, image, beta=0.0, solver="direct")
    assert np.abs(interactive.image() - fresh).max() < 1e-5
    solver = texgrad.GeodesicSolver(spot_domain, progress=lambda stage, fraction: None)
    solver.set_sources(source_vertices=[100])
    seen = []
    solver.solve(progress=lambda stage, fraction: seen.append(stage))
    assert "heat solve" in seen and "distance solve" in seen


def test_the_gil_is_released_during_a_solve(spot_domain, spot_texture_file):
    image = texgrad.read_image(spot_texture_file, dtype=np.float32)
    ticks = []
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.001)

    counter = threading.Thread(target=count)
    counter.start()
    start = time.monotonic()
    texgrad.filter(spot_domain, image, beta=0.0, solver="direct")
    end = time.monotonic()
    done.set()
    counter.join()
    during = [t for t in ticks if start < t < end]
    # A thread holding the GIL for the whole solve would let the counter tick at most once.
    assert len(during) >= 0.2 * (end - start) / 0.001 / 10


def test_tqdm_callback_drives_a_bar(spot_mesh):
    tqdm = pytest.importorskip("tqdm")
    with tqdm.tqdm(total=100, file=io.StringIO()) as bar:
        texgrad.react(spot_mesh, 64, steps=10, progress=texgrad.tqdm_callback(bar))
        assert bar.n == pytest.approx(100)
        assert bar.desc.startswith("react")


def test_solver_calls_from_several_threads_take_turns(spot_domain):
    solver = texgrad.GeodesicSolver(spot_domain, interactive=True)
    solver.set_sources(source_vertices=[100])
    reference = texgrad.GeodesicSolver(spot_domain, interactive=True)
    reference.set_sources(source_vertices=[100])
    for _ in range(8):
        reference.update()
    threads = [threading.Thread(target=lambda: [solver.update() for _ in range(2)])
               for _ in range(4)]
    for thread in threads:
        thread.start()
    for _ in range(20):
        assert np.isfinite(solver.residual())  # reads while the others update
    for thread in threads:
        thread.join()
    assert np.array_equal(solver.distances, reference.distances)


@pytest.mark.parametrize("app", ["filter", "stitch", "seams", "geodesic", "lic"])
def test_every_solving_app_reports_its_solve(square, app):
    image = np.random.default_rng(2).random((32, 32, 3), dtype=np.float32)
    segments = np.zeros((32, 32, 3), np.uint8)
    segments[:, :16, 0] = 255
    segments[:, 16:, 1] = 255
    calls = {
        "filter": lambda p: texgrad.filter(square, image, beta=0.5, progress=p),
        "stitch": lambda p: texgrad.stitch(square, composite=image, segments=segments, progress=p),
        "seams": lambda p: texgrad.seams(square, image, progress=p),
        "geodesic": lambda p: texgrad.geodesic(square, source_uvs=[0.5, 0.5], resolution=32,
                                               progress=p),
        "lic": lambda p: texgrad.lic(square, 32, field=np.array([[1.0, 0.0, 0.0]] * 2),
                                     progress=p),
    }
    seen = []
    calls[app](lambda stage, fraction: seen.append((stage, fraction)))
    solves = [f for stage, f in seen if "solve" in stage or "sharpen" in stage]
    assert solves and solves[-1] == 1.0, seen


def write_two_uv_set_gltf(path, second_set=True):
    """A one-triangle glTF with TEXCOORD_0 and TEXCOORD_1 = TEXCOORD_0 / 2 (or without set 1)."""
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    uv0 = np.array([[0, 1], [1, 1], [0, 0]], np.float32)  # glTF's v points down
    data = positions.tobytes() + uv0.tobytes() + (uv0 / 2).tobytes()
    attributes = {"POSITION": 0, "TEXCOORD_0": 1}
    if second_set:
        attributes["TEXCOORD_1"] = 2
    views = [{"buffer": 0, "byteOffset": offset, "byteLength": length}
             for offset, length in ((0, 36), (36, 24), (60, 24))]
    accessors = [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                  "min": [0, 0, 0], "max": [1, 1, 0]},
                 {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"},
                 {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"}]
    uri = "data:application/octet-stream;base64," + base64.b64encode(data).decode()
    path.write_text(json.dumps({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": attributes}]}],
        "buffers": [{"byteLength": len(data), "uri": uri}],
        "bufferViews": views, "accessors": accessors}))
    return path


def test_read_mesh_reads_the_uv_set_asked(tmp_path):
    path = write_two_uv_set_gltf(tmp_path / "two_sets.gltf")
    first = texgrad.read_mesh(path).atlas_report()["chart_uv_areas"]
    second = texgrad.read_mesh(path, uv_set=1).atlas_report()["chart_uv_areas"]
    assert first == pytest.approx([0.5])
    assert second == pytest.approx([0.125])
    missing = write_two_uv_set_gltf(tmp_path / "one_set.gltf", second_set=False)
    with pytest.raises(ValueError, match="primitive 0 has no TEXCOORD_1"):
        texgrad.read_mesh(missing, uv_set=1)
