"""texgrad.filter's overhead over the C++ call: time and memory on spot at 2048² (issue 26).

    /usr/bin/python3 python/bench/bench_filter.py [--build build/release] [--repetitions 3]

Both sides read spot's texture upsampled to 2048 x 2048 (written once as a PNG), build the
TexelDomain outside the timing (operators assembled once, as `texgrad filter` without a beta map
does), then time the filter with its default options, alternating C++ and Python runs so that a
busy machine slows both alike; wall and CPU time (all threads) are printed, CPU time being the
steadier on a shared machine. Memory: the resident size the call adds, the peak during the call
(VmHWM after resetting it through /proc/self/clear_refs) minus the resident size before it.
"""

import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

SOURCE = pathlib.Path(__file__).resolve().parents[2]


def megabytes(field):
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith(field + ":"):
                return int(line.split()[1]) / 1024.0
    return -1.0


def reset_peak():
    with open("/proc/self/clear_refs", "w") as refs:
        refs.write("5")


def measure_module(build, mesh_path, png, dtype):
    """texgrad.filter the way texgrad_filter_call measures filterTexture: a fresh process, the
    domain built first, one call. Prints one JSON line."""
    sys.path.insert(0, str(pathlib.Path(build) / "python"))
    import numpy as np
    import texgrad

    image = texgrad.read_image(png, dtype=np.dtype(dtype))
    domain = texgrad.TexelDomain(texgrad.read_mesh(mesh_path), image.shape[1], image.shape[0],
                                 keep_piece_integrals=False)
    before = megabytes("VmRSS")
    reset_peak()
    cpu_start, start = time.process_time(), time.perf_counter()
    texgrad.filter(domain, image)
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu_start
    print(json.dumps({"seconds": [seconds], "cpu_seconds": [cpu], "rss_before_mb": before,
                      "peak_mb": megabytes("VmHWM"), "unknowns": domain.unknowns}))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default=str(SOURCE / "build" / "release"))
    parser.add_argument("--mesh", default=str(SOURCE.parent / "shared" / "data" / "spot" /
                                              "spot_triangulated.obj"))
    parser.add_argument("--size", type=int, default=2048)
    parser.add_argument("--repetitions", type=int, default=3)
    parser.add_argument("--dtype", default="float32", choices=["float32", "uint8"])
    parser.add_argument("--module-child", metavar="PNG", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.module_child:
        measure_module(args.build, args.mesh, args.module_child, args.dtype)
        return
    sys.path.insert(0, str(pathlib.Path(args.build) / "python"))
    import numpy as np
    import texgrad

    mesh = texgrad.read_mesh(args.mesh)
    texture = mesh.texture(dtype=np.float32)
    factor = args.size // texture.shape[0]
    texture = np.repeat(np.repeat(texture, factor, axis=0), factor, axis=1)
    folder = tempfile.mkdtemp(prefix="texgrad-bench-")
    png = os.path.join(folder, "texture.png")
    texgrad.write_image(png, texture, bit_depth="8")
    helper = pathlib.Path(args.build) / "python" / "texgrad_filter_call"
    commands = {
        "C++": [str(helper), args.mesh, png, "1"],
        "module": [sys.executable, __file__, "--build", args.build, "--mesh", args.mesh,
                   "--dtype", args.dtype, "--module-child", png],
    }
    runs = {name: [] for name in commands}
    for _ in range(args.repetitions):
        for name, command in commands.items():
            output = subprocess.run(command, capture_output=True, text=True, check=True).stdout
            runs[name].append(json.loads(output))
    seconds = {name: [r["seconds"][0] for r in runs[name]] for name in runs}
    cpu = {name: statistics.median(r["cpu_seconds"][0] for r in runs[name]) for name in runs}
    added = {name: statistics.median(r["peak_mb"] - r["rss_before_mb"] for r in runs[name])
             for name in runs}
    median = {name: statistics.median(seconds[name]) for name in runs}
    channels = texture.shape[2]
    image_mb = args.size * args.size * channels * 4 / 2**20
    print(f"spot at {args.size}², {runs['C++'][0]['unknowns']} unknowns, module input "
          f"{args.dtype}, {args.repetitions} runs each in fresh processes (median)")
    for name, label in (("C++", "C++ filterTexture"), ("module", "texgrad.filter   ")):
        listed = ", ".join(f"{s:.3f}" for s in seconds[name])
        print(f"{label}: {median[name]:.3f} s (runs {listed}), CPU {cpu[name]:.3f} s, adds "
              f"{added[name]:.0f} MB")
    print(f"time ratio module / C++: wall {median['module'] / median['C++']:.3f}, CPU "
          f"{cpu['module'] / cpu['C++']:.3f} (target <= 1.05)")
    extra = added["module"] - added["C++"]
    print(f"memory the module adds beyond the C++ call: {extra:.0f} MB = "
          f"{extra / image_mb:.2f} float images of {image_mb:.0f} MB (target <= 1)")


if __name__ == "__main__":
    main()
