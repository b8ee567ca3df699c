#!/usr/bin/env python3
"""The radiance graph on the real Disney cloud (g = 0.877): pbrt-scenes/results/radiancegraph/disney/.

Run from the repository root after `cargo build --release`, on an otherwise idle machine
(timings are 2 threads; about 25 minutes, most of it the references; 12 once they are cached):

    python3 pbrt-scenes/results/radiancegraph/disney.py
    python3 pbrt-scenes/results/radiancegraph/disney.py published   # section 4 alone, 30 more

The published scene (pbrt-scenes/disney-cloud/disney-cloud.pbrt: sun, sky and the ground disk)
at 160×90. Beyond g = 0.75 the graph holds the similar isotropic medium and carries light until
it leaves the cloud, whatever the scene's maxdepth (src/integrators/radiancegraph/README.md), so
it is compared with volpath at a depth its paths do not reach (DEEP) — the scene's own maxdepth
100 cuts off a quarter of this cloud's light, which the first table shows.

1. volpath's image mean at maxdepth 100, 1000, DEEP (DEPTH_SPP spp, one seed each).
2. One `nimbus compare` at SPP spp, SEEDS seeds, volpath (maxdepth DEEP) against the graph
   (built once, `--precomputed`, so every seed renders from the same graph; its build time
   counted separately), against a volpath reference of REF_SPP spp rendered as two halves
   (their noise removed). The speed-up at equal MAE per frame with the build counted.
3. An orbit of ORBIT cameras around the cloud (the published camera turned about the vertical
   through its target), every frame rendered from the one graph at SPP spp; frames
   ORBIT_MEASURED compared with volpath as in 2 (one seed each, a reference of REF_SPP spp per
   frame) for the time volpath needs to reach the graph's MAE there. The orbit's speed-up with
   its build counted once: volpath's mean time to equal MAE over the measured frames times ORBIT,
   over the build and all ORBIT frames' render times.
4. (`published`) The same comparison at the published scene's 320×180, one seed, its own
   graph and reference: disney/published.md and disney/published/.
Writes disney/results.md, disney/results.json, disney/orbit.png (the frames) and
disney/orbit-times.png; the scene variants, the graph and the cached references live in .work/
(ignored by git).
"""
import json
import math
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
from nimbus_compare import SCENES, THREADS, compare, rel, render_seconds, run, variant  # noqa: E402

WORK = os.path.join(HERE, ".work")
OUT = os.path.join(HERE, "disney")
DEEP = 10000
DEPTH_SPP = 64
SPP = 128
SEEDS = 2
REF_SPP = 512
ORBIT = 16
ORBIT_MEASURED = (0, 4, 8, 12)
# The published camera (disney-cloud.pbrt's LookAt): eye, target, up.
EYE, TARGET, UP = (648.064, -82.473, -63.856), (6.021, 100.043, -43.679), (0.273, 0.962, -0.009)


def scene(depth, width=160, height=90):
    """The published scene at width×height with `depth`, its grid read from pbrt-scenes/disney-cloud/."""
    src = os.path.join(SCENES, "disney-cloud", "disney-cloud.pbrt")
    grid = os.path.relpath(os.path.join(SCENES, "disney-cloud", "wdas_cloud_sixteenth.nvdb"), WORK)
    return variant(src, os.path.join(WORK, f"disney-{width}-d{depth}.pbrt"), [
        (r'"integer maxdepth" \[100\]', f'"integer maxdepth" [{depth}]'),
        (r'"integer xresolution" \[320\]', f'"integer xresolution" [{width}]'),
        (r'"integer yresolution" \[180\]', f'"integer yresolution" [{height}]'),
        (r'"wdas_cloud_sixteenth.nvdb"', f'"{grid}"'),
    ])


def turned(v, a):
    """`v` turned by `a` radians about the vertical (y)."""
    return (v[0] * math.cos(a) + v[2] * math.sin(a), v[1], -v[0] * math.sin(a) + v[2] * math.cos(a))


def orbit_frame(i):
    """The DEEP scene seen from the i-th of ORBIT cameras: the published eye and up turned about
    the vertical through the target, so every frame frames the cloud at the same distance."""
    a = 2 * math.pi * i / ORBIT
    off = turned(tuple(e - t for e, t in zip(EYE, TARGET)), a)
    eye = tuple(t + o for t, o in zip(TARGET, off))
    up = turned(UP, a)
    fmt = " ".join(["{:.3f}"] * 3)
    return variant(scene(DEEP), os.path.join(WORK, f"disney-orbit-{i:02d}.pbrt"), [
        (r"^  648\.064 -82\.473 -63\.856$", "  " + fmt.format(*eye)),
        (r"^  0\.273 0\.962 -0\.009$", "  " + fmt.format(*up)),
    ])


def orbit(graph, build, frame0):
    """Section 3: every frame from `graph`; the measured ones against volpath (frame 0 is the
    comparison of section 2, `frame0`)."""
    frames = []
    for i in range(ORBIT):
        scene_file = orbit_frame(i)
        exr = os.path.join(WORK, f"disney-orbit-{i:02d}.exr")
        frame = {"frame": i, "graph_s": render_seconds(scene_file, exr, "radiancegraph", SPP, ["--precomputed", graph])}
        png = os.path.join(WORK, f"disney-orbit-{i:02d}.png")
        run(["convert", exr, png])
        os.remove(exr)
        frame["png"] = png
        if i in ORBIT_MEASURED:
            if i == 0:
                m = frame0
            else:
                c = compare(scene_file, ["volpath", "radiancegraph"], os.path.join(WORK, f"orbit-{i:02d}"), spp=SPP,
                            seeds=1, reference_spp=REF_SPP, extra=["--precomputed", rel(graph)], keep_images=False)
                m = measured(c)
            frame.update({k: v for k, v in m.items() if k != "graph_s"})  # the frame's own render times it
        frames.append(frame)
    measured_frames = [f for f in frames if "volpath_equal_mae_s" in f]
    volpath_mean = sum(f["volpath_equal_mae_s"] for f in measured_frames) / len(measured_frames)
    graph_total = sum(f["graph_s"] for f in frames)
    return {
        "frames": [{k: v for k, v in f.items() if k != "png"} for f in frames],
        "volpath_equal_mae_mean_s": volpath_mean,
        "graph_render_total_s": graph_total,
        "speedup_with_one_build": ORBIT * volpath_mean / (build + graph_total),
    }, [f["png"] for f in frames]


def measured(c):
    """One comparison's figures: each method's time and MAE, volpath's time to the graph's MAE."""
    r = c.results
    rows = {s["integrator"]: s for s in r["summaries"]}
    g, v = rows["radiancegraph"], rows["volpath"]
    ref_mean = r["reference"]["mean"]
    tte = g["time_to_equal_error"]["mae"]
    return {
        "reference_mean": ref_mean,
        "graph_mae_rel": g["error_noise_removed"]["mae"]["mean"] / ref_mean,
        "graph_mean_offset": g["bias"]["relative"],
        "volpath_mae_rel": v["error_noise_removed"]["mae"]["mean"] / ref_mean,
        "volpath_s": v["seconds"]["mean"],
        "volpath_mean_offset": v["bias"]["relative"],
        "graph_s": g["seconds"]["mean"],
        "volpath_equal_mae_s": tte["baseline_seconds"]["mean"],
    }


def orbit_charts(o, pngs, build):
    """orbit.png: the frames; orbit-times.png: the orbit's cumulative time, graph against volpath."""
    cols = 4
    rows = math.ceil(len(pngs) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 1.9 * rows))
    for ax, (i, png) in zip(axes.flat, enumerate(pngs)):
        ax.imshow(plt.imread(png))
        f = o["frames"][i]
        label = f"frame {i}"
        if "graph_mae_rel" in f:
            label += f": MAE {100 * f['graph_mae_rel']:.1f} %"
        ax.set_title(label, fontsize=8)
        ax.axis("off")
    fig.suptitle(f"The radiance graph, one build, {len(pngs)} cameras around the Disney cloud ({SPP} spp)")
    fig.tight_layout()
    fig.savefig(os.path.join(OUT, "orbit.png"), dpi=100)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6, 4))
    n = list(range(1, ORBIT + 1))
    ax.plot(n, [build + sum(f["graph_s"] for f in o["frames"][:k]) for k in n], "o-", label="radiancegraph (build + frames)")
    ax.plot(n, [k * o["volpath_equal_mae_mean_s"] for k in n], "s-",
            label=f"volpath at the graph's MAE (mean of frames {', '.join(map(str, ORBIT_MEASURED))})")
    ax.set_xlabel("frames of the orbit")
    ax.set_ylabel("seconds (2 threads)")
    ax.set_yscale("log")
    ax.set_title(f"Disney cloud orbit: {o['speedup_with_one_build']:.0f}× at equal MAE, build counted")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(OUT, "orbit-times.png"), dpi=110)
    plt.close(fig)


def image_mean(path):
    """The image mean `nimbus diff` prints (against itself)."""
    out = run(["diff", path, path])
    return float(re.search(r"mean\s+test ([0-9.eE+-]+)", out).group(1))


def published():
    """Section 4: the comparison of section 2 at the published 320×180, one seed."""
    graph = os.path.join(WORK, "disney-320.graph")
    if os.path.exists(graph):
        os.remove(graph)
    c = compare(scene(DEEP, 320, 180), ["volpath", "radiancegraph"], os.path.join(OUT, "published"), spp=SPP,
                seeds=1, reference_spp=REF_SPP, extra=["--precomputed", rel(graph)])
    m = measured(c)
    build = c.results["precomputed"]["prepared_seconds"]
    graph_s = m["graph_s"]
    lines = [
        "# The radiance graph on the Disney cloud at the published 320×180",
        "",
        f"Regenerated by `disney.py published`. As `results.md`'s comparison (volpath to depth {DEEP}, {SPP} spp, "
        f"a {REF_SPP}-spp reference in two halves, its noise removed), one seed, the graph built for this frame.",
        "",
        "| | time (s) | MAE / mean | image mean vs reference |",
        "|---|--:|--:|--:|",
        f"| volpath | {m['volpath_s']:.1f} | {100 * m['volpath_mae_rel']:.1f} % | "
        f"{100 * m['volpath_mean_offset']:+.2f} % |",
        f"| radiancegraph (graph built in {build:.1f} s) | {graph_s:.1f} | {100 * m['graph_mae_rel']:.1f} % | "
        f"{100 * m['graph_mean_offset']:+.2f} % |",
        "",
        f"Volpath needs {m['volpath_equal_mae_s']:.0f} s to reach the graph's MAE: "
        f"{m['volpath_equal_mae_s'] / graph_s:.0f}× the graph's render, "
        f"{m['volpath_equal_mae_s'] / (graph_s + build):.1f}× with its build.",
        "",
        "```sh",
        c.command,
        "```",
        "",
    ]
    open(os.path.join(OUT, "published.md"), "w").write("\n".join(lines))
    print("\n".join(lines))


def main():
    os.makedirs(WORK, exist_ok=True)
    os.makedirs(OUT, exist_ok=True)
    depths = []
    for depth in [100, 1000, DEEP]:
        exr = os.path.join(WORK, f"volpath-d{depth}.exr")
        run(["render", scene(depth), "--spp", str(DEPTH_SPP), "--seed", "21", "--nthreads", THREADS, "--quiet",
             "--outfile", exr])
        depths.append({"maxdepth": depth, "mean": image_mean(exr)})
    graph = os.path.join(WORK, "disney.graph")
    if os.path.exists(graph):
        os.remove(graph)  # built afresh, so its build time is measured
    c = compare(scene(DEEP), ["volpath", "radiancegraph"], os.path.join(OUT, "compare"), spp=SPP, seeds=SEEDS,
                reference_spp=REF_SPP, extra=["--precomputed", rel(graph)])
    r = c.results
    build = r["precomputed"]["prepared_seconds"]
    rows = {s["integrator"]: s for s in r["summaries"]}
    g, v = rows["radiancegraph"], rows["volpath"]
    tte = g["time_to_equal_error"]["mae"]
    volpath_s, graph_s = tte["baseline_seconds"]["mean"], tte["method_seconds"]["mean"]
    ref_mean = r["reference"]["mean"]
    o, pngs = orbit(graph, build, measured(c))
    result = {
        "depths": depths,
        "command": c.command,
        "build_seconds": build,
        "reference_mean": ref_mean,
        "graph": {"seconds": g["seconds"]["mean"], "mae_rel": g["error_noise_removed"]["mae"]["mean"] / ref_mean,
                  "mean_offset": g["bias"]["relative"]},
        "volpath": {"seconds": v["seconds"]["mean"], "mae_rel": v["error_noise_removed"]["mae"]["mean"] / ref_mean,
                    "mean_offset": v["bias"]["relative"]},
        "equal_mae": {"volpath_seconds": volpath_s, "graph_seconds": graph_s,
                      "per_frame_without_build": volpath_s / graph_s,
                      "one_frame_with_build": volpath_s / (graph_s + build)},
        "orbit": o,
    }
    orbit_charts(o, pngs, build)
    json.dump(result, open(os.path.join(OUT, "results.json"), "w"), indent=2)
    e = result["equal_mae"]
    lines = [
        "# The radiance graph on the real Disney cloud (g = 0.877)",
        "",
        "Regenerated by `disney.py` beside this folder. The published scene with its ground, 160×90, 2 threads.",
        "",
        f"## What the scene's maxdepth cuts off (volpath, {DEPTH_SPP} spp, one seed)",
        "",
        "| maxdepth | image mean | against the deepest |",
        "|--:|--:|--:|",
    ] + [f"| {d['maxdepth']} | {d['mean']:.4f} | {100 * (d['mean'] / depths[-1]['mean'] - 1):+.1f} % |" for d in depths] + [
        "",
        f"## The graph against volpath to depth {DEEP} ({SPP} spp, {SEEDS} seeds, reference {REF_SPP} spp in two "
        "halves, its noise removed)",
        "",
        "| | time (s) | MAE / mean | image mean vs reference |",
        "|---|--:|--:|--:|",
        f"| volpath | {v['seconds']['mean']:.1f} | {100 * result['volpath']['mae_rel']:.1f} % | "
        f"{100 * result['volpath']['mean_offset']:+.2f} % |",
        f"| radiancegraph (graph built once in {build:.1f} s) | {g['seconds']['mean']:.1f} | "
        f"{100 * result['graph']['mae_rel']:.1f} % | {100 * result['graph']['mean_offset']:+.2f} % |",
        "",
        f"Equal MAE: volpath needs {volpath_s:.0f} s to reach the graph's MAE, the graph {graph_s:.1f} s to render: "
        f"**{e['per_frame_without_build']:.0f}×** per frame without the build, "
        f"**{e['one_frame_with_build']:.1f}×** for one frame with it.",
        "",
        "```sh",
        c.command,
        "```",
        "",
        f"## An orbit of {ORBIT} cameras from the one graph",
        "",
        f"The published camera turned about the vertical through its target; every frame rendered from the graph "
        f"above ({SPP} spp, seed 1); frames {', '.join(map(str, ORBIT_MEASURED))} compared with volpath as above "
        f"(frame 0 is that comparison; the others one seed, a {REF_SPP}-spp reference each). "
        "![frames](orbit.png)",
        "",
        "| frame | graph render (s) | graph MAE / mean | graph mean vs reference | volpath MAE / mean at "
        f"{SPP} spp | volpath time to the graph's MAE (s) |",
        "|--:|--:|--:|--:|--:|--:|",
    ] + [
        f"| {f['frame']} | {f['graph_s']:.1f} | " + (
            f"{100 * f['graph_mae_rel']:.1f} % | {100 * f['graph_mean_offset']:+.2f} % | "
            f"{100 * f['volpath_mae_rel']:.1f} % | {f['volpath_equal_mae_s']:.0f} |"
            if "graph_mae_rel" in f else "| | | |")
        for f in o["frames"]
    ] + [
        "",
        f"Over the orbit, one build ({build:.1f} s) and {ORBIT} frames ({o['graph_render_total_s']:.0f} s) against "
        f"{ORBIT} × {o['volpath_equal_mae_mean_s']:.0f} s (volpath's mean time to equal MAE over the measured frames): "
        f"**{o['speedup_with_one_build']:.0f}×** at equal MAE, the build counted. ![times](orbit-times.png)",
        "",
    ]
    open(os.path.join(OUT, "results.md"), "w").write("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    os.makedirs(WORK, exist_ok=True)
    os.makedirs(OUT, exist_ok=True)
    published() if sys.argv[1:] == ["published"] else main()
