#!/usr/bin/env python3
"""GPU cost of sun shadows per technique: `demo render --light` of the default scene at
1280x720, shadows on and off (`--no-sun-shadows`) alternated, ROUNDS rounds, each run the
median of 5 frames; prints a Markdown table of the medians over the rounds (GPU ms of every
pass summed, and of the opaque pass). Run from the repository root after
`cargo build --release -p demo`."""
import re, statistics, subprocess, sys

ROUNDS = int(sys.argv[1]) if len(sys.argv) > 1 else 3
TECHNIQUES = ["opaque-only", "wboit-mrt", "wboit-two-pass", "mboit", "stipple", "sorted",
              "sorted-quads", "depth-peeling", "reference", "peel-reference"]

def run(technique, shadows):
    cmd = ["target/release/demo", "render", "--light", "--frames", "5", "--size", "1280x720",
           "--technique", technique, "--out", "/tmp/sun-cost.png"]
    if not shadows:
        cmd.append("--no-sun-shadows")
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    line = next(l for l in out.splitlines() if l.startswith("GPU ms per pass"))
    passes = dict((k, float(v)) for k, v in re.findall(r"([a-z][a-z -]*?) ([0-9.]+)", line.split(":", 1)[1]))
    return passes

rows = []
for t in TECHNIQUES:
    on, off = [], []
    for _ in range(ROUNDS):
        on.append(run(t, True))
        off.append(run(t, False))
    med = lambda runs, f: statistics.median(f(p) for p in runs)
    total = lambda p: sum(p.values())
    opaque = lambda p: p.get("opaque", 0.0)
    tech = lambda p: sum(v for k, v in p.items() if k not in ("opaque", "cutout", "medium", "tonemap"))
    rows.append((t, med(off, total), med(on, total), med(off, opaque), med(on, opaque),
                 med(off, tech), med(on, tech)))
    print(t, rows[-1], file=sys.stderr, flush=True)

print("| technique | all passes, off | on | on / off | opaque pass, off | on | technique's passes, off | on |")
print("|---|---|---|---|---|---|---|---|")
for t, a, b, c, d, e, f in rows:
    print(f"| {t} | {a:.1f} | {b:.1f} | {b / a:.2f}× | {c:.1f} | {d:.1f} | {e:.1f} | {f:.1f} |")
