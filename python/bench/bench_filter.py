"""texgrad.filter's overhead over the C++ call: time and memory on spot at 2048² (issue 26).

    /usr/bin/python3 python/bench/bench_filter.py [--build build/release] [--repetitions 3]

Both sides read spot's texture upsampled to 2048 x 2048 (written once as a PNG), build the
TexelDomain outside the measurement (operators assembled once, as `texgrad filter` without a beta
map does), then run the filter once with its default options, each run in a fresh process,
alternating C++ and Python runs so that a busy machine slows both alike.

Time: wall and CPU time (all threads) of the call, CPU time being the steadier on a shared machine.

Memory: the resident size the call adds, i.e. the peak during the call (VmHWM after resetting it
through /proc/self/clear_refs) minus the resident size before it. With all threads this figure
varies between runs of the same program, on a loaded machine by more than the few MB in question
(2048² on 2 cores at load 11: the C++ call alone added 1124-1146 MB over three runs, and
1144-1204 MB with MALLOC_MMAP_THRESHOLD_=1048576 MALLOC_ARENA_MAX=1): how many TBB tasks hold
their temporaries at the same moment, and in which thread's malloc arena, depends on scheduling.
The memory attributable to the module is therefore also measured in runs pinned to one CPU
(os.sched_setaffinity before exec; oneTBB takes its default concurrency from the affinity mask,
so the library runs without a worker thread and allocates in the same order every run): there
each figure repeats to 0.1 MB, and the difference is what the module holds beyond the C++ call,
its float copy of the input (48 MB at 2048² RGB). Both are printed; "threads" is the process's
thread count after the call (one fewer when pinned: TBB's worker).
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


def status_value(field):
    """The number a field of /proc/self/status holds ("VmRSS" in kB, "Threads"), or -1."""
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    return -1


def megabytes(field):
    return status_value(field) / 1024.0


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
                      "peak_mb": megabytes("VmHWM"), "unknowns": domain.unknowns,
                      "threads": status_value("Threads")}))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default=str(SOURCE / "build" / "release"))
    parser.add_argument("--mesh", default=str(SOURCE.parent / "shared" / "data" / "spot" /
                                              "spot_triangulated.obj"))
    parser.add_argument("--size", type=int, default=2048)
    parser.add_argument("--repetitions", type=int, default=3)
    parser.add_argument("--memory-runs", type=int, default=2,
                        help="runs each pinned to one CPU for the attributable memory")
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
    def run(command, pinned):
        """One fresh process; `pinned` restricts it (and so oneTBB) to one CPU."""
        cpu = min(os.sched_getaffinity(0))
        pin = (lambda: os.sched_setaffinity(0, {cpu})) if pinned else None
        result = subprocess.run(command, capture_output=True, text=True, check=True,
                                preexec_fn=pin)
        return json.loads(result.stdout)

    runs = {name: [] for name in commands}
    pinned = {name: [] for name in commands}
    for _ in range(args.repetitions):
        for name, command in commands.items():
            runs[name].append(run(command, pinned=False))
    for _ in range(args.memory_runs):
        for name, command in commands.items():
            pinned[name].append(run(command, pinned=True))

    def added(r):
        return r["peak_mb"] - r["rss_before_mb"]

    seconds = {name: [r["seconds"][0] for r in runs[name]] for name in runs}
    cpu = {name: statistics.median(r["cpu_seconds"][0] for r in runs[name]) for name in runs}
    median = {name: statistics.median(seconds[name]) for name in runs}
    channels = texture.shape[2]
    image_mb = args.size * args.size * channels * 4 / 2**20
    print(f"spot at {args.size}², {runs['C++'][0]['unknowns']} unknowns, module input "
          f"{args.dtype}, {args.repetitions} runs each in fresh processes (median)")
    labels = (("C++", "C++ filterTexture"), ("module", "texgrad.filter   "))
    for name, label in labels:
        listed = ", ".join(f"{s:.3f}" for s in seconds[name])
        memory = [added(r) for r in runs[name]]
        print(f"{label}: {median[name]:.3f} s (runs {listed}), CPU {cpu[name]:.3f} s, adds "
              f"{statistics.median(memory):.0f} MB (runs {min(memory):.0f}-{max(memory):.0f}, "
              f"{runs[name][0]['threads']} threads)")
    print(f"time ratio module / C++: wall {median['module'] / median['C++']:.3f}, CPU "
          f"{cpu['module'] / cpu['C++']:.3f} (target <= 1.05)")
    extra = statistics.median(added(r) for r in runs["module"]) - statistics.median(
        added(r) for r in runs["C++"])
    print(f"all threads: the module's median adds {extra:.0f} MB more = {extra / image_mb:.2f} "
          f"float images of {image_mb:.0f} MB (run-to-run spread above)")
    if not args.memory_runs:
        return
    for name, label in labels:
        memory = ", ".join(f"{added(r):.1f}" for r in pinned[name])
        print(f"{label} on one CPU: adds {memory} MB ({pinned[name][0]['threads']} threads)")
    extra = statistics.median(added(r) for r in pinned["module"]) - statistics.median(
        added(r) for r in pinned["C++"])
    print(f"memory the module adds beyond the C++ call (one CPU): {extra:.1f} MB = "
          f"{extra / image_mb:.2f} float images of {image_mb:.0f} MB (target <= 1)")


if __name__ == "__main__":
    main()
