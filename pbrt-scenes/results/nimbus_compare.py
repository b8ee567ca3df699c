"""What the results scripts share: the nimbus binary, running it, and `nimbus compare` with its
results.json read back (each method over its seeds, errors with the reference's noise removed,
bias z, time to equal error; schema in docs/compare-results.md).

    sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
    from nimbus_compare import ROOT, compare, run, pm

A script asks `compare` for its numbers rather than computing its own, so every figure it
writes can be reproduced by the command `Comparison.command` prints.
"""

import json
import os
import shlex
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
NIMBUS = os.path.join(ROOT, "target", "release", "nimbus")
SCENES = os.path.join(ROOT, "pbrt-scenes")
REFS = os.path.join(SCENES, "references")
THREADS = "2"


def run(args):
    """Runs nimbus with `args`; its standard output, or the script's exit with its error."""
    if not os.path.exists(NIMBUS):
        sys.exit("build first: cargo build --release")
    r = subprocess.run([NIMBUS] + [str(a) for a in args], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"nimbus {' '.join(map(str, args))} failed:\n{r.stderr}")
    return r.stdout


def rel(path):
    """`path` relative to the repository's root when it is inside it (for printed commands)."""
    p = os.path.abspath(path)
    return os.path.relpath(p, ROOT) if p.startswith(ROOT + os.sep) else p


class Comparison:
    """One `nimbus compare` run: its command and its results.json."""

    def __init__(self, command, out, results):
        self.command = command
        self.out = out
        self.results = results

    def summary(self, integrator, mode):
        for s in self.results["summaries"]:
            if s["integrator"] == integrator and s["mode"] == mode:
                return s
        sys.exit(f"{self.out}: no {integrator} {mode} summary")

    def error(self, integrator, mode, metric="relmse"):
        """The final error's stat over the seeds, with the reference's noise removed when the
        reference came in two halves."""
        s = self.summary(integrator, mode)
        errors = s["error_noise_removed"] or s["error"]
        return errors[metric]

    def ratio(self, integrator, mode):
        """The baseline's relMSE over this method's, seed by seed (mean, standard error)."""
        return self.summary(integrator, mode)["relmse_ratio"]

    def speedup(self, integrator, mode, metric="relmse"):
        """Time to equal error: the baseline's time to reach this method's error over its time."""
        t = self.summary(integrator, mode)["time_to_equal_error"]
        return t[metric]["speedup"] if t else None

    def bias(self, integrator, mode):
        return self.summary(integrator, mode)["bias"]

    def finals(self):
        """The first seed's final checkpoint of each (integrator, mode), as the runs list them."""
        first = self.results["seeds"][0]
        return {(r["integrator"], r["mode"]): r["final"] for r in self.results["runs"] if r["seed"] == first}

    def runs(self, integrator, mode):
        return [r for r in self.results["runs"] if r["integrator"] == integrator and r["mode"] == mode]


def compare(scene, integrators, out, time=None, spp=None, seeds=3, seed=1, reference=None, reference_spp=None,
            html=False, extra=(), keep_images=True):
    """`nimbus compare` of `scene` with `integrators` into `out`: equal `time` seconds and/or
    `spp`, `seeds` independent renders each, against `reference` (a path, or two halves) or a
    volpath reference of `reference_spp` rendered as two halves and cached beside the scene.
    The first seed's EXR outputs become PNGs unless `keep_images` is False; the other seeds'
    images, and every EXR, are removed (results.json keeps their numbers)."""
    args = ["compare", rel(scene), "--integrators", ",".join(integrators), "--seeds", str(seeds), "--seed", str(seed)]
    if time is not None:
        args += ["--time", str(time)]
    if spp is not None:
        args += ["--spp", str(spp)]
    if reference_spp is not None:
        args += ["--reference-spp", str(reference_spp)]
    elif isinstance(reference, (list, tuple)):
        args += ["--reference", ",".join(rel(r) for r in reference)]
    else:
        args += ["--reference", rel(reference)]
    args += list(extra)
    if html:
        args += ["--html", os.path.join(rel(out), "report.html")]
    command = "nimbus " + " ".join(shlex.quote(a) for a in args)
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        run(args + ["--out", out, "--nthreads", THREADS, "--quiet"])
    finally:
        os.chdir(cwd)
    results = json.load(open(os.path.join(out, "results.json")))
    later_seeds = tuple(f"-seed{s}" for s in results["seeds"][1:])
    for f in os.listdir(out):
        stem, ext = os.path.splitext(f)
        later = stem.removesuffix("-diff").endswith(later_seeds) if later_seeds else False
        if ext == ".exr" and keep_images and not later:
            run(["convert", os.path.join(out, f), os.path.join(out, stem + ".png")])
        if ext == ".exr" or (later and ext == ".png"):
            os.remove(os.path.join(out, f))
    return Comparison(command, out, results)


def render_seconds(scene, out, method, spp, extra=()):
    """`nimbus render` of `scene` with `method` at `spp` spp, seed 1, into `out`: the render
    time nimbus reports (a frame's time, no error measured, so no comparison is needed)."""
    import re

    args = ["render", scene, "--integrator", method, "--spp", str(spp), "--seed", "1", "--nthreads", THREADS,
            "--outfile", out] + list(extra)
    r = subprocess.run([NIMBUS] + [str(a) for a in args], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"nimbus {' '.join(map(str, args))} failed:\n{r.stderr}")
    return float(re.search(r"in ([0-9.]+) s", r.stderr).group(1))


def pm(stat, fmt="{:.3g}", unit=""):
    """'mean ± standard error' of a results.json stat (the mean alone for one seed)."""
    if stat is None:
        return "—"
    se = stat.get("standard_error")
    mean = fmt.format(stat["mean"]) + unit
    return mean if se is None else f"{mean} ± {fmt.format(se)}{unit}"


def variant(src, dst, subs):
    """Writes `src` to `dst` with each (regex, replacement) of `subs` applied (each must match)."""
    import re

    text = open(src).read()
    for a, b in subs:
        text, n = re.subn(a, b, text, flags=re.M)
        if n == 0:
            sys.exit(f"{src}: no match for {a}")
    open(dst, "w").write(text)
    return dst
