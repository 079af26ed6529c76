#!/usr/bin/python3
"""Where a texgrad process's heap peak comes from, from a heaptrack recording.

    heaptrack -o /tmp/ht build/rel/texgrad filter MESH TEX --beta 0 -o out.png --json
    bench/heap_peak.py /tmp/ht.zst --texels N      # N: "texels" of the --json summary

heaptrack_print's own peak is useless for the one-shot CLI commands: reuseFreedMemory()
(core/heap_reuse.h) mallocs and frees half the physical memory at start-up to reserve
huge-page address space, so the recorded peak is that reserve. This script replays the trace
without it and prints the live heap at the global peak and at each stage's peak, by stage and
by allocation site (first texgrad frame), in MB and bytes per active texel. A stage is the
outermost known frame of the allocating call stack (STAGES); the stage in progress is that of
the latest allocation. See docs/memory.md for what the figures mean.
"""
import argparse
import collections
import subprocess

RESERVE_BYTES = 5 * 10**9  # an allocation this large is the start-up reserve
# (stage, frame substring), most specific first: the first match in this order names the stage.
STAGES = [
    ("write", "writeTextureOutput"),
    ("write", "writePagedImage"),
    ("write", "writePagedTexture"),
    ("write", "dilateGutters"),
    ("result image", "InteractiveFilter::image"),
    ("result image", "filteredImage"),
    ("result image", "reactionImage"),
    ("result image", "ReactionDiffusion::image"),
    ("cycles", "SystemSolver::solve"),
    ("react steps", "ReactionDiffusion::step"),  # targets and M targets, outside the cycles
    ("stitch solver set-up", "solveStitch"),
    ("stitch (partials)", "stitchPartials"),
    ("stitch (composite)", "stitchComposite"),
    ("project", "projectEachPhoto"),
    ("surface points", "PhotoProjector::PhotoProjector"),
    ("solver set-up", "InteractiveFilter::InteractiveFilter"),
    ("solver set-up", "SystemSolver::initAndUpdate"),
    ("react state", "ReactionDiffusion::ReactionDiffusion"),  # systems, seeded state
    ("solver set-up", "SystemSolver::update"),
    ("geodesic gradients", "GeodesicGradients::GeodesicGradients"),
    ("geodesic stabiliser", "GeodesicGradients::stabiliser"),
    ("geodesic divergence", "GeodesicGradients::divergence"),
    ("geodesic sources", "GeodesicSolver::Impl::setSources"),
    ("geodesic (other)", "geodesicDistance"),
    ("lic M_h, S_h", "assembledFor"),
    ("lic set-up (other)", "LineIntegralConvolution::LineIntegralConvolution"),
    ("lic solve (other)", "LineIntegralConvolution::convolve"),
    ("lic (other)", "licOnce"),  # the one-shot path: noise, b, x, systems, rhs, image
    ("lic (other)", "lineIntegralConvolution"),
    ("filter state", "filterOnce"),  # x, the right-hand side, the system matrix (one-shot)
    ("solve (other)", "filterTexture"),
    ("operators", "TexelDomain::TexelDomain"),
    ("read", "loadTexture"),
    ("read", "loadMesh"),
]
SITES_SHOWN = 16
MIN_SITE_BYTES = 3e6


class Trace:
    """The interpreted heaptrack file: strings, instruction pointers, traces, allocations."""

    def __init__(self, path):
        self.strings, self.functionOfIp, self.traces, self.infos = [], [], [], []
        self.events = []  # (True: alloc / False: free, allocation info index)
        proc = subprocess.Popen(["zstd", "-dc", path], stdout=subprocess.PIPE, text=True,
                                bufsize=1 << 20)
        for line in proc.stdout:
            kind = line[0]
            if kind in "+-":
                self.events.append((kind == "+", int(line[2:], 16)))
            elif kind == "a":
                size, trace = line[2:].split()
                self.infos.append((int(size, 16), int(trace, 16)))
            elif kind == "t":
                ip, parent = line[2:].split()
                self.traces.append((int(ip, 16), int(parent, 16)))
            elif kind == "i":
                parts = line[2:].split()
                self.functionOfIp.append(int(parts[2], 16) if len(parts) > 2 else 0)
            elif kind == "s":
                self.strings.append(line[2:].rstrip("\n").partition(" ")[2])
        self.stageOf = {}

    def frames(self, trace):
        out = []
        while trace:
            ip, trace = self.traces[trace - 1]
            function = self.functionOfIp[ip - 1]
            out.append(self.strings[function - 1] if function else "?")
        return out

    def stage(self, trace):
        if trace not in self.stageOf:
            frames = self.frames(trace)
            self.stageOf[trace] = next(
                (name for name, key in STAGES if any(key in f for f in frames)), "other")
        return self.stageOf[trace]

    def site(self, trace):
        texgrad = [f for f in self.frames(trace) if f.startswith("texgrad::")]
        if not texgrad:
            return "(no texgrad frame: libraries, TBB)"
        return texgrad[0].replace("(anonymous namespace)", "{anon}").split("(")[0]

    def replay(self):
        """Yields (event index, live bytes, per-trace live Counter) after every event."""
        perTrace, live, started = collections.Counter(), 0, False
        for n, (alloc, info) in enumerate(self.events):
            size, trace = self.infos[info]
            if size >= RESERVE_BYTES:
                started = started or not alloc
                continue
            delta = size if alloc else -size
            perTrace[trace] += delta
            live += delta
            yield n, live, trace, alloc, started, perTrace


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("trace", help="heaptrack output (.zst)")
    parser.add_argument("--texels", type=int, required=True, help="active texels of the run")
    args = parser.parse_args()
    t = Trace(args.trace)
    # Pass 1: the event at which each stage (and the whole run) peaks.
    peaks, current = {}, "other"
    for n, live, trace, alloc, started, _ in t.replay():
        if not started:
            continue
        if alloc and t.stage(trace) != "other":
            current = t.stage(trace)
        for key in (current, "GLOBAL"):
            if live > peaks.get(key, (0, -1))[0]:
                peaks[key] = (live, n)
    # Pass 2: what is live at those events.
    at = collections.defaultdict(list)
    for key, (_, n) in peaks.items():
        at[n].append(key)
    snapshots = {}
    for n, _, _, _, _, perTrace in t.replay():
        for key in at.get(n, []):
            snapshots[key] = {k: b for k, b in perTrace.items() if b > 0}
    mb, per = 1e6, args.texels
    print(f"active texels {per:,}")
    print("peak live heap while each stage allocates:")
    for key, (live, n) in sorted(peaks.items(), key=lambda kv: kv[1][1]):
        print(f"  {key:14s} {live / mb:8.1f} MB {live / per:6.1f} B/texel")
    for key in ["GLOBAL"] + [k for k in peaks if k != "GLOBAL"]:
        snap = snapshots[key]
        byStage, bySite = collections.Counter(), collections.Counter()
        for trace, b in snap.items():
            byStage[t.stage(trace)] += b
            bySite[(t.stage(trace), t.site(trace))] += b
        print(f"\n== at the peak of {key}: {sum(snap.values()) / mb:.1f} MB")
        for stage, b in byStage.most_common():
            print(f"   allocated in {stage:14s} {b / mb:8.1f} MB {b / per:6.1f} B/texel")
        for (stage, site), b in bySite.most_common(SITES_SHOWN):
            if b < MIN_SITE_BYTES:
                break
            print(f"   {b / mb:8.1f} MB {b / per:6.1f} B/t  [{stage}] {site}")


if __name__ == "__main__":
    main()
