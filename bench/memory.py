#!/usr/bin/python3
"""Peak memory and stage times of `texgrad filter` (default settings, --beta 0) at large sizes.

Prints one Markdown row per run: active texels, wall time per stage (the CLI's --json), peak
resident memory from /usr/bin/time -v and from the CLI's own "peak_rss_bytes", and bytes per
active texel (issue 28). Textures are the shared meshes' own, upscaled with
`oiiotool --resize` into --work (a build folder; never commit them).

A size above --max-gb by a dry estimate (texels from the coverage of a smaller run of the same
mesh, or of the UV area, times --estimate-bytes per texel) is skipped, not run: the kernel
would kill it. Run from the source tree, e.g.
    bench/memory.py --texgrad build/rel/texgrad --sizes 2048,4096 --lpshead-sizes 4096
The defaults are issue 28's rows: spot at 2048² to 16384² (each size's estimate from the
measured rate of the one before), lpshead at 8192² (after 4096²), and --max-gb 0.95 of the
machine's memory (MemTotal; 21 where /proc/meminfo is missing): on a 24 GB machine spot at
16384² runs, at about 23.2 GB.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

SOURCE = Path(__file__).resolve().parent.parent
DATA = Path(os.environ.get("TEXGRAD_SHARED_DATA", SOURCE.parent / "shared" / "data"))
# Mesh, its texture, and the share of the texture's texels the atlas covers at 1024^2
# (INDEX.md's UV area: a first guess for the dry estimate before any run of that mesh).
MESHES = {
    "spot": ("spot/spot_triangulated.obj", "spot/spot_texture.png", 0.4913),
    "lpshead": ("lpshead/head_triangulated.obj", "lpshead/lambertian_1k.jpg", 0.9165),
}
STAGES = ("read", "operators", "solve", "write", "total")
BYTES_PER_GB = 1e9
BYTES_PER_KIB = 1024


def default_max_gb():
    """0.95 of the machine's memory in GB (MemTotal), or 21 without /proc/meminfo."""
    try:
        with open("/proc/meminfo") as meminfo:
            for line in meminfo:
                if line.startswith("MemTotal:"):
                    return 0.95 * int(line.split()[1]) * BYTES_PER_KIB / BYTES_PER_GB
    except OSError:
        pass
    return 21.0


def parse_sizes(text):
    return [int(s) for s in text.split(",") if s.strip()]


def texture_at(mesh, size, work):
    """The mesh's texture resized to size x size (made once, kept in `work`)."""
    out = work / f"{mesh}_{size}.png"
    if not out.exists():
        source = DATA / MESHES[mesh][1]
        subprocess.run(["oiiotool", str(source), "--resize", f"{size}x{size}", "-o", str(out)],
                       check=True)
    return out


def run_filter(texgrad, mesh, size, work):
    """Runs filter under /usr/bin/time -v; returns the row's figures."""
    texture = texture_at(mesh, size, work)
    out = work / f"{mesh}_{size}_filtered.png"
    cmd = ["/usr/bin/time", "-v", str(texgrad), "filter", str(DATA / MESHES[mesh][0]),
           str(texture), "--beta", "0", "--out", str(out), "--json", "--quiet"]
    start = time.monotonic()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.monotonic() - start
    if proc.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{proc.stderr}")
    match = re.search(r"Maximum resident set size \(kbytes\): (\d+)", proc.stderr)
    summary = json.loads(proc.stdout)
    return {
        "texels": summary["texels"],
        "stages": summary["stages"],
        "time_rss": int(match.group(1)) * BYTES_PER_KIB,
        "cli_rss": summary.get("peak_rss_bytes", 0),
        "wall": wall,
    }


def load_average():
    with open("/proc/loadavg") as f:
        return f.read().split()[0]


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--texgrad", default=str(SOURCE / "build" / "rel" / "texgrad"))
    parser.add_argument("--work", default=str(SOURCE / "build" / "bench-memory"),
                        help="folder for the upscaled textures and outputs (not committed)")
    parser.add_argument("--sizes", default="2048,4096,8192,16384",
                        help="spot sizes, e.g. 2048,4096,8192,16384")
    parser.add_argument("--lpshead-sizes", default="4096,8192", help="lpshead sizes ('' for none)")
    parser.add_argument("--max-gb", type=float, default=default_max_gb(),
                        help="skip a size whose dry estimate exceeds this (GB; default: 0.95 "
                             "of MemTotal)")
    parser.add_argument("--estimate-bytes", type=float, default=400.0,
                        help="bytes per active texel for the dry estimate before any run")
    parser.add_argument("--dry-run", action="store_true", help="print the estimates only")
    args = parser.parse_args()
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)

    print("| mesh | size | active texels | read s | operators s | solve s | write s | total s "
          "| us/texel | peak RSS (time -v) MB | peak RSS (CLI) MB | B/texel | load |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    cases = [("spot", s) for s in parse_sizes(args.sizes)]
    cases += [("lpshead", s) for s in parse_sizes(args.lpshead_sizes)]
    measured = {}  # mesh -> (texels per texture texel, bytes per texel) of its last run
    for mesh, size in cases:
        coverage, per_texel = measured.get(mesh, (MESHES[mesh][2], args.estimate_bytes))
        estimate = coverage * size * size * per_texel / BYTES_PER_GB
        if args.dry_run or estimate > args.max_gb:
            reason = "dry run" if args.dry_run else f"skipped: over --max-gb {args.max_gb:g}"
            print(f"| {mesh} | {size}² | ~{coverage * size * size:,.0f} | | | | | | | "
                  f"~{estimate * 1e3:,.0f} (estimate, {reason}) | | ~{per_texel:.0f} | |")
            continue
        load = load_average()
        row = run_filter(args.texgrad, mesh, size, work)
        texels, stages = row["texels"], row["stages"]
        per_texel = row["time_rss"] / texels
        measured[mesh] = (texels / (size * size), per_texel)
        times = " | ".join(f"{stages.get(s, float('nan')):.2f}" for s in STAGES)
        micros = stages.get("total", float("nan")) * 1e6 / texels
        print(f"| {mesh} | {size}² | {texels:,} | {times} | {micros:.2f} | "
              f"{row['time_rss'] / 1e6:,.0f} | "
              f"{row['cli_rss'] / 1e6:,.0f} | {per_texel:.0f} | {load} |", flush=True)


if __name__ == "__main__":
    main()
