#!/usr/bin/env python3
"""Regenerates pbrt-scenes/results/radiancegraph/: the radiance-graph method against volpath.

Run from the repository root after `cargo build --release` (needs matplotlib), on an otherwise
idle machine (timings are 2 threads):

    python3 pbrt-scenes/results/radiancegraph/run.py

Every error is one `nimbus compare` (pbrt-scenes/results/nimbus_compare.py): SEEDS seeds per
method, each seed building its own graph (so the spread counts the graph's noise), against a
volpath reference rendered as two independent halves whose own noise is removed from the
errors; numbers are mean ± standard error over the seeds.

Scenes: the thesis's cube (scenes/cube.pbrt, its config scenes/cube.json) and nimbus's
graph-constraints cloud (pbrt-scenes/graph-constraints-cloud.pbrt with maxdepth 10, config
scenes/cloud.json).

1. Accuracy and speed at SPP spp against volpath (maxdepth 10, REF_SPP-spp reference), with the
   thesis's delta tracking along camera rays and with nimbus's collision estimator: folders
   <scene>/ and <scene>-collision/ (images, error images, charts, results.*). Graph sizes and
   bytes per node and edge come from one `nimbus graph build` of each.
2. The same with denser graphs (scenes/*-dense.json): how much of the error is the graph's own
   noise.
3. The thesis's Sec. 5.4 sweeps: node radius on the cloud (radiusModifier scaled), volume size
   on the cube (node radius fixed): node-radius.png, volume-size.png.
4. An orbit of 16 cameras around the cloud rendered from one saved graph (ORBIT_RES² pixels per
   frame; `nimbus render --precomputed`), timed against volpath, with the frame at which building
   the graph has paid for itself: orbit.png.
Writes results.md and results.json. Scene variants and their cached references live in
.work/ beside this script (ignored by git; delete it to render the references anew).
"""
import json
import math
import os
import shutil
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
from nimbus_compare import SCENES, compare, pm, render_seconds, run, variant  # noqa: E402

WORK = os.path.join(HERE, ".work")
SEEDS = 3
SPP = 128
# The accuracy references, two halves of REF_SPP / 2: their noise is removed from the errors,
# but the less there is, the less the removal has to do.
REF_SPP = 8192
# The volume-size sweep's references (the largest volumes are slow).
SWEEP_REF_SPP = 2048
# The orbit's frame size: a frame a user renders, not the 96-pixel accuracy renders (the
# per-frame saving grows with the pixels; the graph's build does not).
ORBIT_RES = 256
RADII = [0.5, 1, 2, 4, 8]
VOLUME_SCALES = [0.5, 1, 2, 4]


def graph_stats(scene):
    """One `nimbus graph build` of `scene` with the config beside it (written by `scene_dir`),
    into a `graph/` folder beside it: the graph file and its statistics (nodes, edges, build
    time, bytes per node and edge at the peak)."""
    config, out_dir = scene.replace(".pbrt", ".json"), os.path.join(os.path.dirname(scene), "graph")
    run(["graph", "build", scene, "--config", config, "--out", out_dir, "--quiet"])
    stem = os.path.splitext(os.path.basename(config))[0]
    stats = json.load(open(os.path.join(out_dir, f"{stem}_stats.json")))
    graph = [p for p in os.listdir(out_dir) if p.startswith(stem + "_d") and p.endswith(".txt")][0]
    return os.path.join(out_dir, graph), {
        "nodes": stats["amounts"]["vertices"],
        "edges": stats["amounts"]["edges"],
        "build_s": stats["nimbus"]["seconds"],
        "bytes_per_node": stats["nimbus"]["build_peak_bytes_per_node"],
        "bytes_per_edge": stats["nimbus"]["build_peak_bytes_per_edge"],
        "node_radius": stats["sizes"]["node_radius"],
        "scene_radius": stats["sizes"]["scene_radius"],
    }


def scene_dir(name, pbrt_src, config_src, subs=(), config_edit=None):
    """WORK/<name>/<stem>.pbrt with its graph config beside it as <stem>.json (radiancegraph
    reads the config beside the scene), the scene's `subs` and the config's `config_edit`
    applied. The scene's path."""
    d = os.path.join(WORK, name)
    os.makedirs(d, exist_ok=True)
    stem = os.path.splitext(os.path.basename(pbrt_src))[0]
    scene = variant(pbrt_src, os.path.join(d, f"{stem}.pbrt"), list(subs) or [(r"^", "")])
    config = json.load(open(config_src))
    if config_edit:
        config_edit(config)
    json.dump(config, open(os.path.join(d, f"{stem}.json"), "w"), indent=2)
    return scene


def out_dir(name):
    d = os.path.join(HERE, name)
    shutil.rmtree(d, ignore_errors=True)
    return d


def summary_row(c, method="radiancegraph", mode="equal-spp"):
    """A method's errors over the seeds, relative to the reference's mean, and its times."""
    s = c.summary(method, mode)
    ref_mean = c.results["reference"]["mean"]
    row = {
        "command": c.command,
        "seconds": s["seconds"],
        "setup_seconds": s["setup_seconds"],
        "mae": c.error(method, mode, "mae"),
        "mpe": c.error(method, mode, "mpe"),
        "mne": c.error(method, mode, "mne"),
        "relmse": c.error(method, mode, "relmse"),
        "bias": c.bias(method, mode),
        "ref_mean": ref_mean,
    }
    if method != "volpath" and c.results["baseline"] == "volpath":
        row["speedup_mae"] = c.speedup(method, mode, "mae")
        v = c.summary("volpath", mode)
        row["volpath_seconds"] = v["seconds"]
        row["volpath_mae"] = c.error("volpath", mode, "mae")
    return row


def rel_pm(stat, ref_mean):
    """A stat of an absolute error as 'x.xx ± y.yy %' of the reference's mean."""
    scaled = {**stat, "mean": stat["mean"] / ref_mean}
    if stat.get("standard_error") is not None:
        scaled["standard_error"] = stat["standard_error"] / ref_mean
    return pm(scaled, "{:.2%}").replace("%", "") + " %"


def bias_text(b):
    return f"{b['relative']:+.2%} (z {b['bias_z']:.1f})" if b.get("bias_z") is not None else f"{b['relative']:+.2%}"


def main():
    os.makedirs(WORK, exist_ok=True)
    results = {"seeds": SEEDS, "spp": SPP, "reference_spp": REF_SPP}
    cloud_src = os.path.join(SCENES, "graph-constraints-cloud.pbrt")
    maxdepth10 = [(r'"integer maxdepth" \[ 12 \]', '"integer maxdepth" [ 10 ]')]
    cases = {
        "cloud": (cloud_src, os.path.join(HERE, "scenes", "cloud.json"), maxdepth10),
        "cube": (os.path.join(HERE, "scenes", "cube.pbrt"), os.path.join(HERE, "scenes", "cube.json"), []),
    }
    collision = [(r"^Integrator [^\n]*", 'Integrator "radiancegraph" "string estimator" "collision"')]

    # 1. Accuracy and speed at SPP spp, each seed building its graph.
    main_rows, references = [], {}
    for name, (src, config, subs) in cases.items():
        scene = scene_dir(name, src, config, subs)
        _, stats = graph_stats(scene)
        c = compare(scene, ["volpath", "radiancegraph"], out_dir(name), spp=SPP, seeds=SEEDS, reference_spp=REF_SPP,
                    html=True)
        references[name] = [os.path.join(os.path.dirname(scene), os.path.basename(p)) for p in c.results["reference"]["paths"]]
        # The collision variant names radiancegraph in its Integrator line, so volpath is not
        # rendered from it (it would lose the scene's maxdepth): its times come from above.
        col_scene = scene_dir(f"{name}-collision", src, config, list(subs) + collision)
        cc = compare(col_scene, ["radiancegraph"], out_dir(f"{name}-collision"), spp=SPP, seeds=SEEDS,
                     reference=references[name])
        main_rows.append({"scene": name, **stats, "graph": summary_row(c), "volpath": summary_row(c, "volpath"),
                          "collision": summary_row(cc)})
    results["accuracy"] = main_rows

    # 2. Denser graphs (4x the light paths, 4x the direct-light samples per node).
    dense_rows = []
    for name, (src, _, subs) in cases.items():
        dense = os.path.join(HERE, "scenes", f"{name}-dense.json")
        row = {"scene": name}
        for est, extra in [("graph", []), ("collision", collision)]:
            scene = scene_dir(f"{name}-dense-{est}", src, dense, list(subs) + extra)
            if est == "graph":
                _, row["stats"] = graph_stats(scene)
            c = compare(scene, ["radiancegraph"], out_dir(f"{name}-dense-{est}"), spp=SPP, seeds=SEEDS,
                        reference=references[name], keep_images=False)
            row[est] = summary_row(c)
            shutil.rmtree(c.out, ignore_errors=True)
        dense_rows.append(row)
    results["accuracy_dense"] = dense_rows

    # 3a. Node radius (thesis Sec. 5.4, node size) on the cloud: radiusModifier scaled by k.
    src, config, subs = cases["cloud"]
    base_modifier = json.load(open(config))["graphBuilder"]["radiusModifier"]
    radius_rows = []
    for k in RADII:
        def edit(cfg, k=k):
            cfg["graphBuilder"]["radiusModifier"] = base_modifier * k
        scene = scene_dir(f"radius-{k}", src, config, subs, edit)
        _, stats = graph_stats(scene)
        c = compare(scene, ["radiancegraph"], out_dir(f"radius-{k}"), spp=SPP, seeds=SEEDS, reference=references["cloud"],
                    keep_images=False)
        radius_rows.append({"k": k, "radius": stats["node_radius"], **stats, **summary_row(c)})
        shutil.rmtree(c.out, ignore_errors=True)
    results["node_radius"] = radius_rows

    # 3b. Volume size (thesis Sec. 5.4) on the cube: the volume scaled by s, the node radius
    # kept (radiusModifier / s: the default radius is the scene radius / 500), light paths kept.
    src, config, _ = cases["cube"]
    cube_modifier = json.load(open(config))["graphBuilder"]["radiusModifier"]
    volume_rows = []
    for s in VOLUME_SCALES:
        def edit(cfg, s=s):
            cfg["graphBuilder"]["radiusModifier"] = cube_modifier / s
        scene = scene_dir(f"size-{s}", src, config,
                          [(r"Scale 5 5 5", f"Scale {5 * s} {5 * s} {5 * s}"), (r"LookAt 20 0 0", f"LookAt {20 * s} 0 0")], edit)
        _, stats = graph_stats(scene)
        c = compare(scene, ["volpath", "radiancegraph"], out_dir(f"size-{s}"), spp=SPP, seeds=SEEDS,
                    reference_spp=SWEEP_REF_SPP, keep_images=False)
        volume_rows.append({"scale": s, "volume_radius": stats["scene_radius"], **stats, **summary_row(c)})
        shutil.rmtree(c.out, ignore_errors=True)
    results["volume_size"] = volume_rows

    # 4. Orbit: 16 cameras around the cloud from one saved graph.
    src, config, subs = cases["cloud"]
    scene = scene_dir("orbit", src, config, subs)
    graph, stats = graph_stats(scene)
    orbit = []
    for i in range(16):
        a = 2 * math.pi * i / 16
        eye = (3.6 * math.cos(a), 0.8, 3.6 * math.sin(a))
        frame = variant(scene, os.path.join(WORK, "orbit", f"frame-{i}.pbrt"), [
            (r"^LookAt [^\n]*", f"LookAt {eye[0]:.4f} {eye[1]:.4f} {eye[2]:.4f}  0 0 0  0 1 0"),
            (r'"integer xresolution" \[ 96 \] "integer yresolution" \[ 96 \]',
             f'"integer xresolution" [ {ORBIT_RES} ] "integer yresolution" [ {ORBIT_RES} ]'),
        ])
        times = {}
        for method, extra in [("radiancegraph", ["--precomputed", graph]), ("volpath", [])]:
            img = os.path.join(WORK, "orbit", f"frame-{i}-{method}.exr")
            times[method] = render_seconds(frame, img, method, SPP, extra)
            if method == "radiancegraph" and i % 4 == 0:
                run(["convert", img, os.path.join(HERE, f"orbit-{i:02d}.png")])
            os.remove(img)
        orbit.append({"frame": i, "graph_s": times["radiancegraph"], "volpath_s": times["volpath"]})
    build_s = stats["build_s"]
    per_frame_gain = sum(o["volpath_s"] - o["graph_s"] for o in orbit) / len(orbit)
    break_even = math.ceil(build_s / per_frame_gain) if per_frame_gain > 0 else None
    results["orbit"] = {"frames": orbit, "build_s": build_s, "break_even_frames": break_even}

    with open(os.path.join(HERE, "results.json"), "w") as f:
        json.dump(results, f, indent=2)
    charts(radius_rows, volume_rows, orbit, build_s, break_even)
    table(results)


def charts(radius_rows, volume_rows, orbit, build_s, break_even):
    def error_panel(ax, xs, rows, xlabel, title):
        for k, c in [("mae", "black"), ("mpe", "green"), ("mne", "red")]:
            ys = [r[k]["mean"] / r["ref_mean"] for r in rows]
            es = [(r[k]["standard_error"] or 0) / r["ref_mean"] for r in rows]
            ax.errorbar(xs, ys, yerr=es, fmt="o-", color=c, capsize=3, label=k.upper())
        ax.set_xscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(f"error / reference mean ({SEEDS} seeds, ± SE)")
        ax.set_title(title)
        ax.legend()

    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    rs = [r["radius"] for r in radius_rows]
    error_panel(ax[0], rs, radius_rows, "node radius", "cloud: error against node radius")
    ax[1].plot(rs, [r["nodes"] for r in radius_rows], "o-", label="nodes")
    ax[1].plot(rs, [r["edges"] for r in radius_rows], "s-", label="edges")
    ax[1].set_xscale("log")
    ax[1].set_yscale("log")
    ax[1].set_xlabel("node radius")
    ax[1].set_title("graph size against node radius")
    ax[1].legend()
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "node-radius.png"), dpi=110)

    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    vr = [r["volume_radius"] for r in volume_rows]
    error_panel(ax[0], vr, volume_rows, "volume radius (node radius fixed)", "cube: error against volume size")
    ax[1].plot(vr, [r["build_s"] for r in volume_rows], "o-", label="graph build")
    ax[1].plot(vr, [r["seconds"]["mean"] - r["setup_seconds"]["mean"] for r in volume_rows], "s-",
               label=f"graph render ({SPP} spp)")
    ax[1].plot(vr, [r["volpath_seconds"]["mean"] for r in volume_rows], "^-", label=f"volpath render ({SPP} spp)")
    ax[1].set_xscale("log")
    ax[1].set_yscale("log")
    ax[1].set_xlabel("volume radius")
    ax[1].set_ylabel("seconds")
    ax[1].set_title("time against volume size")
    ax[1].legend()
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "volume-size.png"), dpi=110)

    fig, ax = plt.subplots(figsize=(6, 4))
    frames = list(range(0, 17))
    ax.plot(frames, [build_s + sum(o["graph_s"] for o in orbit[:n]) for n in frames], "o-", label="graph (build + frames)")
    ax.plot(frames, [sum(o["volpath_s"] for o in orbit[:n]) for n in frames], "s-", label="volpath")
    ax.set_xlabel("frames of the orbit")
    ax.set_ylabel("cumulative seconds")
    ax.set_title(f"orbit of 16 cameras: break-even at frame {break_even}")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "orbit.png"), dpi=110)


def table(results):
    f2 = "{:.2f}"
    lines = [
        "# radiancegraph against volpath", "",
        f"Generated by `run.py` (see its docstring). Every error is one `nimbus compare` over {SEEDS} seeds "
        f"(mean ± standard error; each seed builds its own graph) against a volpath reference (maxdepth 10, "
        f"{REF_SPP} spp as two independent halves) with the reference's noise removed; renders at {SPP} spp, "
        "2 threads. Render time excludes the graph build; speed-up at equal MAE includes it.", "",
        "| scene | nodes | edges | build s | B/node | B/edge | graph render s | volpath render s | speed-up per frame | "
        "graph MAE/mean | MPE/mean | MNE/mean | mean vs ref (z) | volpath MAE/mean | speed-up at equal MAE, build included |",
        "|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"]
    for r in results["accuracy"]:
        g, v = r["graph"], r["volpath"]
        render_s = g["seconds"]["mean"] - g["setup_seconds"]["mean"]
        m = g["ref_mean"]
        lines.append(
            f"| {r['scene']} | {r['nodes']} | {r['edges']} | {r['build_s']:.2f} | {r['bytes_per_node']:.1f} | "
            f"{r['bytes_per_edge']:.1f} | {render_s:.2f} | {v['seconds']['mean']:.2f} | {v['seconds']['mean'] / render_s:.1f}× | "
            f"{rel_pm(g['mae'], m)} | {rel_pm(g['mpe'], m)} | {rel_pm(g['mne'], m)} | {bias_text(g['bias'])} | "
            f"{rel_pm(v['mae'], m)} | {pm(g['speedup_mae'], '{:.2f}', '×')} |")
    lines += ["", "With the collision estimator along camera rays (`\"string estimator\" \"collision\"`):", "",
              "| scene | render s | speed-up per frame | MAE/mean | MPE/mean | MNE/mean | mean vs ref (z) |",
              "|---|--:|--:|--:|--:|--:|--:|"]
    for r in results["accuracy"]:
        c = r["collision"]
        render_s = c["seconds"]["mean"] - c["setup_seconds"]["mean"]
        m = c["ref_mean"]
        volpath_s = r["volpath"]["seconds"]["mean"]
        lines.append(f"| {r['scene']} | {render_s:.2f} | {volpath_s / render_s:.1f}× | {rel_pm(c['mae'], m)} | "
                     f"{rel_pm(c['mpe'], m)} | {rel_pm(c['mne'], m)} | {bias_text(c['bias'])} |")
    lines += ["", "Denser graphs (`scenes/*-dense.json`: 4× the light paths and 4× the direct-light samples per node; "
              "the cube is homogeneous, so both estimators are one):", "",
              "| scene | nodes | edges | build s | graph MAE/mean | mean vs ref (z) | collision MAE/mean | mean vs ref (z) |",
              "|---|--:|--:|--:|--:|--:|--:|--:|"]
    for r in results["accuracy_dense"]:
        g, c, s = r["graph"], r["collision"], r["stats"]
        m = g["ref_mean"]
        lines.append(f"| {r['scene']} | {s['nodes']} | {s['edges']} | {s['build_s']:.2f} | {rel_pm(g['mae'], m)} | {bias_text(g['bias'])} | "
                     f"{rel_pm(c['mae'], m)} | {bias_text(c['bias'])} |")
    lines += ["", "Node radius (cloud; radiusModifier scaled):", "",
              "| radius | nodes | edges | build s | MAE/mean | MPE/mean | MNE/mean | mean vs ref (z) |", "|--:|--:|--:|--:|--:|--:|--:|--:|"]
    for r in results["node_radius"]:
        m = r["ref_mean"]
        lines.append(f"| {r['radius']:.4f} | {r['nodes']} | {r['edges']} | {f2.format(r['build_s'])} | {rel_pm(r['mae'], m)} | "
                     f"{rel_pm(r['mpe'], m)} | {rel_pm(r['mne'], m)} | {bias_text(r['bias'])} |")
    lines += ["", f"Volume size (cube, node radius fixed; references {SWEEP_REF_SPP} spp in two halves):", "",
              "| volume radius | nodes | edges | build s | graph render s | volpath s | MAE/mean | MPE/mean | MNE/mean | mean vs ref (z) |",
              "|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"]
    for r in results["volume_size"]:
        m = r["ref_mean"]
        render_s = r["seconds"]["mean"] - r["setup_seconds"]["mean"]
        lines.append(f"| {r['volume_radius']:.2f} | {r['nodes']} | {r['edges']} | {r['build_s']:.2f} | {render_s:.2f} | "
                     f"{r['volpath_seconds']['mean']:.2f} | {rel_pm(r['mae'], m)} | {rel_pm(r['mpe'], m)} | {rel_pm(r['mne'], m)} | "
                     f"{bias_text(r['bias'])} |")
    o = results["orbit"]
    tg = sum(f["graph_s"] for f in o["frames"]) / len(o["frames"])
    tv = sum(f["volpath_s"] for f in o["frames"]) / len(o["frames"])
    lines += ["", f"Orbit (cloud, 16 cameras of {ORBIT_RES}×{ORBIT_RES} at {SPP} spp, one graph loaded with "
              f"`--precomputed`): graph {tg:.2f} s/frame, volpath {tv:.2f} s/frame, build {o['build_s']:.2f} s: "
              f"break-even at frame {o['break_even_frames']}.", "",
              "The commands behind the tables (run from the repository root; scenes in .work/):", ""]
    for r in results["accuracy"]:
        lines += [f"- {r['scene']}: `{r['graph']['command']}`", f"- {r['scene']}, collision: `{r['collision']['command']}`"]
    lines.append("")
    with open(os.path.join(HERE, "results.md"), "w") as f:
        f.write("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
