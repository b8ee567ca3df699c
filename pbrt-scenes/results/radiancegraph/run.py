#!/usr/bin/env python3
"""Regenerates pbrt-scenes/results/radiancegraph/: the radiance-graph method against volpath.

Run from the repository root after `cargo build --release` (needs matplotlib):

    python3 pbrt-scenes/results/radiancegraph/run.py

Scenes: the thesis's cube (scenes/cube.pbrt, its config scenes/cube.json) and nimbus's
graph-constraints cloud (pbrt-scenes/graph-constraints-cloud.pbrt with maxdepth 10, config
scenes/cloud.json). For each: graph build, graph and volpath renders at 128 spp, MAE/MPE/MNE
against a volpath reference (maxdepth 10, 8192 spp) and error images (green: graph brighter,
red: darker). Then the thesis's Sec. 5.4 sweeps as charts (node radius on the cloud, volume size
on the cube) and an orbit of 16 cameras around the cloud rendered from one saved graph, with
the frame count at which building the graph has paid for itself (at ORBIT_RES² pixels per frame). Writes results.md,
results.json and the charts; intermediate renders go to a temporary directory that is removed.
Timings are this machine's (2 threads).
"""
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", "..", ".."))
NIMBUS = os.path.join(ROOT, "target", "release", "nimbus")
SPP = 128
# The accuracy references: at 8192 spp their own noise (volpath's MAE falls as 1/sqrt(spp)) is
# a quarter of a 128-spp render's, so the MAE measured is mostly the method's.
REF_SPP = 8192
# The volume-size sweep's references (four of them, the largest volumes are slow).
SWEEP_REF_SPP = 1024
THREADS = "2"
# The orbit's frame size: a frame a user renders, not the 96-pixel accuracy renders (the
# per-frame saving grows with the pixels; the graph's build does not).
ORBIT_RES = 256


def run(args):
    r = subprocess.run([NIMBUS] + args, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"nimbus {' '.join(args)} failed:\n{r.stderr}")
    return r


def render(scene, out, spp, extra=()):
    r = run(["render", scene, "--spp", str(spp), "--seed", "1", "--nthreads", THREADS, "--outfile", out] + list(extra))
    m = re.search(r"in ([0-9.]+) s", r.stderr)
    return float(m.group(1))


def diff(test, ref, out_png=None):
    args = ["diff", test, ref] + (["--out", out_png] if out_png else [])
    text = run(args).stdout
    val = lambda k: float(re.search(rf"^{k}\s+([-0-9.e+]+)", text, re.M).group(1))
    mean = re.search(r"^mean\s+test ([-0-9.e+]+) reference ([-0-9.e+]+)", text, re.M)
    return {"mae": val("MAE"), "mpe": val("MPE"), "mne": val("MNE"), "mean": float(mean.group(1)), "ref_mean": float(mean.group(2))}


def build(scene, config, out_dir, extra=()):
    run(["graph", "build", scene, "--config", config, "--out", out_dir, "--quiet"] + list(extra))
    stem = os.path.splitext(os.path.basename(config))[0]
    with open(os.path.join(out_dir, f"{stem}_stats.json")) as f:
        stats = json.load(f)
    graph = [p for p in os.listdir(out_dir) if p.startswith(stem + "_d") and p.endswith(".txt")][0]
    return os.path.join(out_dir, graph), stats


def scene_variant(src, dst, replacements):
    with open(src) as f:
        text = f.read()
    for a, b in replacements:
        assert re.search(a, text), f"{a} not in {src}"
        text = re.sub(a, b, text)
    with open(dst, "w") as f:
        f.write(text)
    return dst


def main():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if not os.path.exists(NIMBUS):
        sys.exit("build nimbus first: cargo build --release")
    work = tempfile.mkdtemp(prefix="nimbus-radiancegraph-")
    try:
        results = {}
        cloud = scene_variant(
            os.path.join(ROOT, "pbrt-scenes", "graph-constraints-cloud.pbrt"),
            os.path.join(work, "cloud.pbrt"),
            [(r'"integer maxdepth" \[ 12 \]', '"integer maxdepth" [ 10 ]')],
        )
        shutil.copy(os.path.join(HERE, "scenes", "cloud.json"), os.path.join(work, "cloud.json"))
        cube = scene_variant(os.path.join(HERE, "scenes", "cube.pbrt"), os.path.join(work, "cube.pbrt"), [])
        shutil.copy(os.path.join(HERE, "scenes", "cube.json"), os.path.join(work, "cube.json"))

        # 1. Accuracy and speed at 128 spp.
        main_rows = []
        for name, scene in [("cloud", cloud), ("cube", cube)]:
            ref = os.path.join(work, f"{name}-ref.exr")
            t_ref = render(scene, ref, REF_SPP)
            graph, stats = build(scene, os.path.join(work, f"{name}.json"), work)
            g_img, v_img = os.path.join(work, f"{name}-graph.exr"), os.path.join(work, f"{name}-volpath.exr")
            t_graph = render(scene, g_img, SPP, ["--integrator", "graph", "--graph-data", graph])
            t_vp = render(scene, v_img, SPP)
            eg, ev = diff(g_img, ref, os.path.join(HERE, f"{name}-graph-error.png")), diff(v_img, ref, os.path.join(HERE, f"{name}-volpath-error.png"))
            # nimbus's collision estimator along camera rays (same graph, same integral).
            col_scene = scene_variant(scene, os.path.join(work, f"{name}-collision.pbrt"), [(r'Integrator [^\n]*', 'Integrator "radiancegraph" "string estimator" "collision"')])
            c_img = os.path.join(work, f"{name}-collision.exr")
            t_col = render(col_scene, c_img, SPP, ["--graph-data", graph])
            ec = diff(c_img, ref, os.path.join(HERE, f"{name}-collision-error.png"))
            run(["convert", g_img, os.path.join(HERE, f"{name}-graph.png")])
            run(["convert", ref, os.path.join(HERE, f"{name}-reference.png")])
            row = {
                "scene": name,
                "nodes": stats["amounts"]["vertices"],
                "edges": stats["amounts"]["edges"],
                "build_s": stats["nimbus"]["seconds"],
                "bytes_per_node": stats["nimbus"]["build_peak_bytes_per_node"],
                "bytes_per_edge": stats["nimbus"]["build_peak_bytes_per_edge"],
                "graph_s": t_graph,
                "collision_s": t_col,
                "volpath_s": t_vp,
                "reference_s": t_ref,
                "graph": eg,
                "collision": ec,
                "volpath": ev,
            }
            main_rows.append(row)
        results["accuracy"] = main_rows

        # 1b. The same with denser graphs (4x the light paths, 4x the direct-light samples per
        # node: scenes/*-dense.json): how far the error is the graph's own noise.
        dense_rows = []
        for name, scene in [("cloud", cloud), ("cube", cube)]:
            d = os.path.join(work, f"{name}-dense")
            os.makedirs(d)
            shutil.copy(os.path.join(HERE, "scenes", f"{name}-dense.json"), os.path.join(d, f"{name}-dense.json"))
            graph, stats = build(scene, os.path.join(d, f"{name}-dense.json"), d)
            ref = os.path.join(work, f"{name}-ref.exr")
            row = {"scene": name, "nodes": stats["amounts"]["vertices"], "edges": stats["amounts"]["edges"], "build_s": stats["nimbus"]["seconds"]}
            for est in ["graph", "collision"]:
                src = scene if est == "graph" else os.path.join(work, f"{name}-collision.pbrt")
                img = os.path.join(d, f"{est}.exr")
                row[f"{est}_s"] = render(src, img, SPP, ["--integrator", "graph", "--graph-data", graph] if est == "graph" else ["--graph-data", graph])
                row[est] = diff(img, ref)
            dense_rows.append(row)
        results["accuracy_dense"] = dense_rows

        # 2. Node radius sweep (thesis Table 5.4, node size) on the cloud.
        base = next(r for r in main_rows if r["scene"] == "cloud")
        with open(os.path.join(work, "cloud_stats.json")) as f:
            default_radius = json.load(f)["sizes"]["node_radius"]
        sweep = []
        for k in [0.5, 1, 2, 4, 8]:
            d = os.path.join(work, f"radius-{k}")
            os.makedirs(d)
            r = default_radius * k
            graph, stats = build(cloud, os.path.join(work, "cloud.json"), d, ["--node-radius", f"{r:.6g}"])
            img = os.path.join(d, "g.exr")
            t = render(cloud, img, SPP, ["--integrator", "graph", "--graph-data", graph])
            e = diff(img, os.path.join(work, "cloud-ref.exr"))
            sweep.append({"radius": r, "nodes": stats["amounts"]["vertices"], "edges": stats["amounts"]["edges"], "build_s": stats["nimbus"]["seconds"], "render_s": t, **e})
        results["node_radius"] = sweep

        # 3. Volume size sweep (thesis Table 5.4, volume size) on the cube: the volume scaled,
        # node radius and light paths fixed.
        with open(os.path.join(work, "cube_stats.json")) as f:
            cube_radius = json.load(f)["sizes"]["node_radius"]
        vsweep = []
        for s in [0.5, 1, 2, 4]:
            d = os.path.join(work, f"size-{s}")
            os.makedirs(d)
            scene = scene_variant(cube, os.path.join(d, "cube.pbrt"), [(r"Scale 5 5 5", f"Scale {5 * s} {5 * s} {5 * s}"), (r"LookAt 20 0 0", f"LookAt {20 * s} 0 0")])
            shutil.copy(os.path.join(work, "cube.json"), os.path.join(d, "cube.json"))
            ref = os.path.join(d, "ref.exr")
            render(scene, ref, SWEEP_REF_SPP)
            graph, stats = build(scene, os.path.join(d, "cube.json"), d, ["--node-radius", f"{cube_radius:.6g}"])
            img = os.path.join(d, "g.exr")
            t = render(scene, img, SPP, ["--integrator", "graph", "--graph-data", graph])
            tv = render(scene, os.path.join(d, "v.exr"), SPP)
            e = diff(img, ref)
            vsweep.append({"scale": s, "volume_radius": stats["sizes"]["scene_radius"], "nodes": stats["amounts"]["vertices"], "edges": stats["amounts"]["edges"], "build_s": stats["nimbus"]["seconds"], "render_s": t, "volpath_s": tv, **e})
        results["volume_size"] = vsweep

        # 4. Orbit: 16 cameras around the cloud from one saved graph.
        graph = os.path.join(work, "cloud_d10.txt")
        orbit = []
        for i in range(16):
            a = 2 * math.pi * i / 16
            eye = (3.6 * math.cos(a), 0.8, 3.6 * math.sin(a))
            scene = scene_variant(cloud, os.path.join(work, f"orbit-{i}.pbrt"), [
                (r"LookAt [^\n]*", f"LookAt {eye[0]:.4f} {eye[1]:.4f} {eye[2]:.4f}  0 0 0  0 1 0"),
                (r'"integer xresolution" \[ 96 \] "integer yresolution" \[ 96 \]', f'"integer xresolution" [ {ORBIT_RES} ] "integer yresolution" [ {ORBIT_RES} ]'),
            ])
            tg = render(scene, os.path.join(work, f"orbit-{i}-g.exr"), SPP, ["--integrator", "graph", "--graph-data", graph])
            tv = render(scene, os.path.join(work, f"orbit-{i}-v.exr"), SPP)
            orbit.append({"frame": i, "graph_s": tg, "volpath_s": tv})
            if i % 4 == 0:
                run(["convert", os.path.join(work, f"orbit-{i}-g.exr"), os.path.join(HERE, f"orbit-{i:02d}.png")])
        build_s = base["build_s"]
        per_frame_gain = sum(o["volpath_s"] - o["graph_s"] for o in orbit) / len(orbit)
        break_even = math.ceil(build_s / per_frame_gain) if per_frame_gain > 0 else None
        results["orbit"] = {"frames": orbit, "build_s": build_s, "break_even_frames": break_even}

        with open(os.path.join(HERE, "results.json"), "w") as f:
            json.dump(results, f, indent=2)

        # Charts.
        def error_panel(ax, xs, rows, xlabel, title):
            for k, c in [("mae", "black"), ("mpe", "green"), ("mne", "red")]:
                ax.plot(xs, [r[k] / r["ref_mean"] for r in rows], "o-", color=c, label=k.upper())
            ax.set_xscale("log")
            ax.set_xlabel(xlabel)
            ax.set_ylabel("error / reference mean")
            ax.set_title(title)
            ax.legend()

        fig, ax = plt.subplots(1, 2, figsize=(10, 4))
        rs = [s["radius"] for s in sweep]
        error_panel(ax[0], rs, sweep, "node radius", "cloud: error against node radius")
        ax[1].plot(rs, [s["nodes"] for s in sweep], "o-", label="nodes")
        ax[1].plot(rs, [s["edges"] for s in sweep], "s-", label="edges")
        ax[1].set_xscale("log")
        ax[1].set_yscale("log")
        ax[1].set_xlabel("node radius")
        ax[1].set_title("graph size against node radius")
        ax[1].legend()
        fig.tight_layout()
        fig.savefig(os.path.join(HERE, "node-radius.png"), dpi=110)

        fig, ax = plt.subplots(1, 2, figsize=(10, 4))
        vr = [s["volume_radius"] for s in vsweep]
        error_panel(ax[0], vr, vsweep, "volume radius (node radius fixed)", "cube: error against volume size")
        ax[1].plot(vr, [s["build_s"] for s in vsweep], "o-", label="graph build")
        ax[1].plot(vr, [s["render_s"] for s in vsweep], "s-", label=f"graph render ({SPP} spp)")
        ax[1].plot(vr, [s["volpath_s"] for s in vsweep], "^-", label=f"volpath render ({SPP} spp)")
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
        cg = [build_s + sum(o["graph_s"] for o in orbit[:n]) for n in frames]
        cv = [sum(o["volpath_s"] for o in orbit[:n]) for n in frames]
        ax.plot(frames, cg, "o-", label="graph (build + frames)")
        ax.plot(frames, cv, "s-", label="volpath")
        ax.set_xlabel("frames of the orbit")
        ax.set_ylabel("cumulative seconds")
        ax.set_title(f"orbit of 16 cameras: break-even at frame {break_even}")
        ax.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(HERE, "orbit.png"), dpi=110)

        # Table.
        lines = ["# radiancegraph against volpath", "", "Generated by `run.py` (see its docstring). Errors against a volpath reference "
                 f"(maxdepth 10, {REF_SPP} spp); renders at {SPP} spp, 2 threads.", "",
                 "| scene | nodes | edges | build s | B/node | B/edge | graph render s | volpath render s | speed-up | graph MAE/mean | MPE | MNE | mean vs ref | volpath MAE/mean |",
                 "|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"]
        for r in main_rows:
            g, v = r["graph"], r["volpath"]
            lines.append(
                f"| {r['scene']} | {r['nodes']} | {r['edges']} | {r['build_s']:.2f} | {r['bytes_per_node']:.1f} | {r['bytes_per_edge']:.1f} | "
                f"{r['graph_s']:.2f} | {r['volpath_s']:.2f} | {r['volpath_s'] / r['graph_s']:.1f}× | {g['mae'] / g['ref_mean']:.2%} | "
                f"{g['mpe']:.2e} | {g['mne']:.2e} | {g['mean'] / g['ref_mean'] - 1:+.2%} | {v['mae'] / v['ref_mean']:.2%} |")
        lines += ["", "With the collision estimator along camera rays (`\"string estimator\" \"collision\"`, same graphs):", "",
                  "| scene | render s | speed-up | MAE/mean | MPE | MNE | mean vs ref |", "|---|--:|--:|--:|--:|--:|--:|"]
        for r in main_rows:
            c = r["collision"]
            lines.append(f"| {r['scene']} | {r['collision_s']:.2f} | {r['volpath_s'] / r['collision_s']:.1f}× | {c['mae'] / c['ref_mean']:.2%} | {c['mpe']:.2e} | {c['mne']:.2e} | {c['mean'] / c['ref_mean'] - 1:+.2%} |")
        lines += ["", "Denser graphs (`scenes/*-dense.json`: 4× the light paths and 4× the direct-light samples per node; the cube is homogeneous, so both estimators are one):", "",
                  "| scene | nodes | edges | build s | graph MAE/mean | mean vs ref | collision MAE/mean | mean vs ref | collision render s |", "|---|--:|--:|--:|--:|--:|--:|--:|--:|"]
        for r in dense_rows:
            g, c = r["graph"], r["collision"]
            lines.append(f"| {r['scene']} | {r['nodes']} | {r['edges']} | {r['build_s']:.2f} | {g['mae'] / g['ref_mean']:.2%} | {g['mean'] / g['ref_mean'] - 1:+.2%} | "
                         f"{c['mae'] / c['ref_mean']:.2%} | {c['mean'] / c['ref_mean'] - 1:+.2%} | {r['collision_s']:.2f} |")
        lines += ["", "Node radius (cloud):", "", "| radius | nodes | edges | MAE/mean | MPE | MNE |", "|--:|--:|--:|--:|--:|--:|"]
        for s in sweep:
            lines.append(f"| {s['radius']:.4f} | {s['nodes']} | {s['edges']} | {s['mae'] / s['ref_mean']:.2%} | {s['mpe']:.2e} | {s['mne']:.2e} |")
        lines += ["", "Volume size (cube, node radius fixed):", "", "| volume radius | nodes | edges | build s | graph s | volpath s | MAE/mean | MPE | MNE |", "|--:|--:|--:|--:|--:|--:|--:|--:|--:|"]
        for s in vsweep:
            lines.append(f"| {s['volume_radius']:.2f} | {s['nodes']} | {s['edges']} | {s['build_s']:.2f} | {s['render_s']:.2f} | {s['volpath_s']:.2f} | {s['mae'] / s['ref_mean']:.2%} | {s['mpe']:.2e} | {s['mne']:.2e} |")
        tg = sum(o["graph_s"] for o in orbit) / 16
        tv = sum(o["volpath_s"] for o in orbit) / 16
        lines += ["", f"Orbit (cloud, 16 cameras of {ORBIT_RES}×{ORBIT_RES} at {SPP} spp, one graph): graph {tg:.2f} s/frame, volpath {tv:.2f} s/frame, build {build_s:.2f} s: "
                  f"break-even at frame {break_even}.", ""]
        with open(os.path.join(HERE, "results.md"), "w") as f:
            f.write("\n".join(lines))
        print("\n".join(lines))
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
