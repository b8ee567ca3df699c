#!/usr/bin/env python3
"""Regenerates pbrt-scenes/results/headlines/: every headline ratio the README quotes for a
research method, each measured by one `nimbus compare` command over three seeds against a
volpath reference rendered as two independent halves, the reference's noise removed.

Run from anywhere after `cargo build --release`, on an otherwise idle machine (2 threads):

    python3 pbrt-scenes/results/headlines/run.py [--tabulate] [name ...]

With names, only those headlines are measured again (the others are kept from headlines.json).
`--tabulate` measures nothing: it rewrites the tables from each folder's results.json.
References are cached beside the scenes (`<scene>.volpath-<N>spp-seed<S>.exr`, ignored by git):
the first run renders them (the candle's two 16384-spp halves take about 15 minutes).
Writes headlines.md, headlines.json and one compare folder per headline (images as PNG, the
HTML report, results.json).
"""

import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from nimbus_compare import SCENES, Comparison, compare, pm  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
SEEDS = 3


def scene(name):
    return os.path.join(SCENES, name + ".pbrt")


# (name, method, what the README claims, compare arguments, the rows to report: (label,
# integrator, mode, kind) with kind "ratio" (baseline relMSE / its), "speedup" (time to equal
# relMSE), "speedup-mae", "time-ratio" (baseline's time / its at equal spp), "bias").
PATHGRAPH = [("per sample (1 spp): relMSE ratio", "pathgraph", "equal-spp", "ratio"),
             ("equal time (1.5 s): relMSE ratio", "pathgraph", "equal-time", "ratio"),
             ("equal time (1.5 s): time to equal relMSE", "pathgraph", "equal-time", "speedup"),
             ("mean vs reference (z)", "pathgraph", "equal-time", "bias")]
HEADLINES = [
    ("pathgraph-cloud", "pathgraph", "the heterogeneous cloud under sun and sky",
     dict(scene=scene("cloud-sun-sky"), integrators=["volpath", "pathgraph"], spp=1, time=1.5,
          reference_spp=4096), PATHGRAPH),
    ("pathgraph-wax", "pathgraph", "milk in a glass sphere under a small light",
     dict(scene=scene("wax-small-light"), integrators=["volpath", "pathgraph"], spp=1, time=1.5,
          reference_spp=32768), PATHGRAPH),
    ("pathgraph-fog", "pathgraph", "fog around an emitter",
     dict(scene=scene("fog-emitter"), integrators=["volpath", "pathgraph"], spp=1, time=1.5,
          reference_spp=4096), PATHGRAPH),
    ("guided-candle", "guided", "the candle (milk, g 0.85, in glass, small light) at the issue's 60 s",
     dict(scene=scene("wax-small-light"), integrators=["volpath", "guided"], time=60, reference_spp=32768),
     [("equal time (60 s): relMSE ratio", "guided", "equal-time", "ratio"),
      ("equal time (60 s): time to equal relMSE", "guided", "equal-time", "speedup"),
      ("mean vs reference (z)", "guided", "equal-time", "bias")]),
    ("radiancegraph-cloud", "radiancegraph", "the shipped cloud with its graph config, 128 spp, graph built per seed",
     dict(scene=scene("graph-constraints-cloud"), integrators=["volpath", "radiancegraph"], spp=128,
          reference_spp=4096),
     [("equal spp (128): volpath's time / its (build included)", "radiancegraph", "equal-spp", "time-ratio"),
      ("equal spp (128): MAE, % of the mean", "radiancegraph", "equal-spp", "mae-percent"),
      ("time to equal MAE", "radiancegraph", "equal-spp", "speedup-mae"),
      ("mean vs reference (z)", "radiancegraph", "equal-spp", "bias")]),
]


def value(c, integrator, mode, kind):
    """(text, number) of one reported row."""
    if kind == "ratio":
        s = c.ratio(integrator, mode)
        return pm(s, "{:.2f}", "×"), s
    if kind in ("speedup", "speedup-mae"):
        metric = "mae" if kind == "speedup-mae" else "relmse"
        e = c.summary(integrator, mode)["time_to_equal_error"][metric]
        s = e["speedup"]
        note = f" (volpath's time extrapolated for {e['extrapolated']} of {SEEDS} seeds)" if e["extrapolated"] else ""
        return pm(s, "{:.2f}", "×") + note, s
    if kind == "time-ratio":
        base = c.summary("volpath", mode)["seconds"]["mean"]
        t = c.summary(integrator, mode)["seconds"]
        s = {"mean": base / t["mean"], "standard_error": None, "n": t["n"]}
        return f"{base / t['mean']:.2f}× ({base:.2f} s / {pm(t, '{:.2f}', ' s')})", s
    if kind == "mae-percent":
        e = c.error(integrator, mode, "mae")
        mean = c.results["reference"]["mean"]
        s = {"mean": 100 * e["mean"] / mean, "standard_error": e["standard_error"] and 100 * e["standard_error"] / mean,
             "n": e["n"]}
        return pm(s, "{:.2f}", " %"), s
    if kind == "bias":
        b = c.bias(integrator, mode)
        z, dof = b["bias_z"], b["offset"]["n"] - 1
        text = f"{100 * b['relative']:+.2f} %"
        return (text + f" (z {z:+.1f}, a t with {dof} dof)" if z is not None else text), b
    raise ValueError(kind)


def main():
    tabulate = "--tabulate" in sys.argv[1:]
    only = set(a for a in sys.argv[1:] if a != "--tabulate")
    path = os.path.join(HERE, "headlines.json")
    old = json.load(open(path)) if os.path.exists(path) else {}
    results = {}
    for name, method, what, args, rows in HEADLINES:
        if only and name not in only and name in old:
            results[name] = old[name]
            continue
        out = os.path.join(HERE, name)
        args = dict(args)
        if tabulate:
            c = Comparison(old[name]["command"], out, json.load(open(os.path.join(out, "results.json"))))
        else:
            c = compare(args.pop("scene"), args.pop("integrators"), out, seeds=SEEDS, html=True, **args)
        results[name] = {
            "method": method,
            "what": what,
            "command": c.command,
            "rows": [{"label": label, "text": value(c, i, m, k)[0], "value": value(c, i, m, k)[1]}
                     for label, i, m, k in rows],
        }
        json.dump(results | {k: v for k, v in old.items() if k not in results}, open(path, "w"), indent=1)
    json.dump(results, open(path, "w"), indent=1)
    md = ["# Headline ratios", "",
          f"Generated by `run.py`: each is one `nimbus compare` command (run from the repository root), "
          f"{SEEDS} independent seeds per method (its training or graph build redone for each), against a "
          "volpath reference rendered as two independent halves whose own noise is removed from every error "
          "(docs/compare-results.md). Values are mean ± standard error over the seeds; ratios are volpath's "
          "relMSE over the method's, seed by seed (above 1: the method is better); time to equal relMSE is the "
          "time volpath needs to reach the method's final error over the method's time. The mean's z is a "
          f"Student t with {SEEDS - 1} degrees of freedom: beyond ±4.3 is a bias at the 5 % level; three seeds "
          "are weak evidence either way (volpath against its own reference on the cloud read z 4.1 with three "
          "seeds, 0.2 with ten). 2 threads.", ""]
    for name, method, what, _, _ in HEADLINES:
        r = results[name]
        md += [f"## {method}: {what}", "", "```sh", r["command"], "```", "",
               f"Images, error images, curves and the table: [{name}/report.html]({name}/report.html), "
               f"[{name}/results.md]({name}/results.md).", "",
               "| measure | value |", "|---|--:|"]
        md += [f"| {row['label']} | {row['text']} |" for row in r["rows"]]
        md.append("")
    open(os.path.join(HERE, "headlines.md"), "w").write("\n".join(md))
    print("\n".join(md))


if __name__ == "__main__":
    main()
