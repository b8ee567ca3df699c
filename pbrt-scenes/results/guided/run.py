#!/usr/bin/env python3
"""Regenerates pbrt-scenes/results/guided/ (path guiding in media against volpath).

Run from anywhere after `cargo build --release` (needs matplotlib), on an otherwise idle
machine (timings are 2 threads):

    python3 pbrt-scenes/results/guided/run.py

1. Equal time (EQUAL_TIME s, training included) and equal spp (64) with `nimbus compare` on the
   paper's Candle case (wax-small-light: forward-scattering milk in a glass sphere, small light),
   an isotropic medium in the same glass (g = 0: MIS mode), and a cloud (cloud-sun-sky: not
   guided by default, and guided everywhere with `refractedshare 0`), and the dense cloud of
   pbrt-scenes/pbrt-v4-references (grid-cloud) guided everywhere: folders <case>/.
   The candle again at the issue's 60-s budget (LONG_TIME), against a volpath reference of two
   LONG_REF_SPP halves rendered here (cached in the temporary folder), with the reference's own
   noise taken out as well: folder candle-60s/.
2. The paper's Fig. 16: MIS vs RIS vs selective, equal time, as a sweep of g in the glass.
3. The paper's Fig. 18: error against the number of candidates M at equal spp and equal time.
4. The paper's Fig. 19: error against training iterations at equal spp (render time), with the
   training time.
5. The paper's Fig. 20: the glass made rough (roughness 0.01, 0.1, 0.5), equal time.
6. Every pbrt-scenes scene at equal time: the "never more than 10 % worse" table.
Writes results.md and results.json beside this script. References: the shipped ones
(pbrt-scenes/references) or volpath at REF_SPP rendered here for the variants (seed 7).
"""

import csv
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", "..", ".."))
NIMBUS = os.path.join(ROOT, "target", "release", "nimbus")
SCENES = os.path.join(ROOT, "pbrt-scenes")
REFS = os.path.join(SCENES, "references")
THREADS = "2"
SEED = "1"
EQUAL_TIME = 8.0
REF_SPP = 1024
# The budget, on the candle, against a reference of LONG_REF_SPP (at 60 s the shipped
# 4096-spp reference's own noise is about 40 % of volpath's measured error).
LONG_TIME = 60.0
LONG_REF_SPP = 16384
LONG_REF_SEEDS = (11, 12)


def run(args):
    r = subprocess.run([NIMBUS] + args, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"nimbus {' '.join(args)} failed:\n{r.stderr}")
    return r.stdout


def variant(src, dst, subs):
    text = open(src).read()
    for a, b in subs:
        text, n = re.subn(a, b, text, flags=re.M)
        if n == 0:
            sys.exit(f"{src}: no match for {a}")
    open(dst, "w").write(text)
    return dst


def guided(params=""):
    """Substitution making the scene's integrator `guided` with `params` (volpath, compared
    against it, reads the same line and ignores guided's parameters)."""
    return (r'^Integrator "volpath"', f'Integrator "guided" {params}')


def reference(scene, out):
    run(["render", scene, "--integrator", "volpath", "--spp", str(REF_SPP), "--seed", "7", "--outfile", out,
         "--quiet", "--nthreads", THREADS])
    return out


def long_reference(scene, seed):
    """A volpath render of `scene` at LONG_REF_SPP with `seed`, kept in the system's temporary
    folder (keyed by the scene's text) and reused by later runs: a 16384-spp half takes about
    seven minutes, and volpath's images change only with a fix the parity tests would show."""
    cache = os.path.join(tempfile.gettempdir(), "nimbus-guided-results-cache")
    os.makedirs(cache, exist_ok=True)
    key = hashlib.sha256(open(scene, "rb").read()).hexdigest()[:16]
    out = os.path.join(cache, f"{key}-{LONG_REF_SPP}spp-seed{seed}.exr")
    if not os.path.exists(out):
        run(["render", scene, "--integrator", "volpath", "--spp", str(LONG_REF_SPP), "--seed", str(seed),
             "--outfile", out + ".part.exr", "--quiet", "--nthreads", THREADS])
        os.replace(out + ".part.exr", out)
    return out


def diff_relmse(a, b):
    return float(re.search(r"relMSE\s+([0-9.e+-]+)", run(["diff", a, b])).group(1))


def compare(scene, ref, out, integrators, time_s=None, spp=None, keep_images=True):
    args = ["compare", scene, "--integrators", ",".join(integrators), "--reference", ref, "--seed", SEED,
            "--nthreads", THREADS, "--out", out, "--quiet"]
    if time_s:
        args += ["--time", str(time_s)]
    if spp:
        args += ["--spp", str(spp)]
    run(args)
    rows = list(csv.DictReader(open(os.path.join(out, "results.csv"))))
    for f in os.listdir(out):
        if f.endswith(".exr"):
            exr = os.path.join(out, f)
            if keep_images:
                run(["convert", exr, exr[:-4] + ".png"])
            os.remove(exr)
    return rows


def finals(rows):
    return {(r["integrator"], r["mode"]): r for r in rows if r["final"] == "true"}


def training(scene, work):
    """(seconds, photons, media line) of guided's training on `scene`, from --stats."""
    img = os.path.join(work, "training.exr")
    out = run(["render", scene, "--integrator", "guided", "--spp", "1", "--outfile", img,
               "--quiet", "--stats", "--seed", SEED, "--nthreads", THREADS])
    os.remove(img)
    m = re.search(r"trained \(([0-9]+) photons in [0-9]+ rounds, ([0-9]+) deposits, ([0-9.]+) s training\)", out)
    media = re.search(r"guide media (.*)", out).group(1)
    return float(m.group(3)), int(m.group(1)), media


def main():
    if not os.path.exists(NIMBUS):
        sys.exit("build first: cargo build --release")
    work = tempfile.mkdtemp(prefix="nimbus-guided-")
    results = {}
    wax = os.path.join(SCENES, "wax-small-light.pbrt")
    wax_ref = os.path.join(REFS, "wax-small-light.exr")
    md = ["# guided against volpath", "",
          f"Generated by `run.py` (see its docstring); 2 threads, seed {SEED}; equal time is {EQUAL_TIME} s per "
          "method counted from before the scene is built, so guided's training is inside it. relMSE as "
          "`nimbus compare` defines it. Error ratios are volpath : guided (above 1: guided better).", ""]
    try:
        # 1. The three cases.
        iso = variant(wax, os.path.join(work, "iso.pbrt"),
                      [(r'"float g" \[ 0.85 \]', '"float g" [ 0 ]'),
                       (r'"rgb sigma_s" \[ 3.0 3.2 3.5 \]', '"rgb sigma_s" [ 0.6 0.64 0.7 ]')])
        cloud = os.path.join(SCENES, "cloud-sun-sky.pbrt")
        cloud_all = variant(cloud, os.path.join(work, "cloud-all.pbrt"), [guided('"float refractedshare" 0')])
        pbrt_refs = os.path.join(SCENES, "pbrt-v4-references")
        dense = variant(os.path.join(pbrt_refs, "scenes", "grid-cloud.pbrt"), os.path.join(work, "grid-cloud-all.pbrt"),
                        [guided('"float refractedshare" 0')])
        cases = [
            ("candle", "milk (g 0.85) in glass, small light: the paper's Candle", wax, wax_ref),
            ("isotropic", "isotropic milk (g 0) in glass, small light: MIS mode", iso,
             reference(iso, os.path.join(work, "iso-ref.exr"))),
            ("cloud", "cloud under sun and sky (not guided: 0 % refracted)", cloud,
             os.path.join(REFS, "cloud-sun-sky.exr")),
            ("cloud-guided", "the same cloud guided everywhere (refractedshare 0)", cloud_all,
             os.path.join(REFS, "cloud-sun-sky.exr")),
            ("dense-cloud-guided", "pbrt-v4-references' grid-cloud (dense, g 0.6-0.7, sun) guided everywhere",
             dense, os.path.join(pbrt_refs, "images", "grid-cloud.exr")),
        ]
        md += [f"## Equal time ({EQUAL_TIME} s) and equal spp (64)", "",
               "| case | integrator | training | spp in time | relMSE (equal time) | MAE | mean vs ref | "
               "relMSE at 64 spp | time at 64 spp |",
               "|---|---|--:|--:|--:|--:|--:|--:|--:|"]
        results["cases"] = {}
        for name, what, scene, ref in cases:
            out = os.path.join(HERE, name)
            shutil.rmtree(out, ignore_errors=True)
            rows = compare(scene, ref, out, ["volpath", "guided"], time_s=EQUAL_TIME, spp=64)
            f = finals(rows)
            t_train, photons, media = training(scene, work)
            case = {"what": what, "training_seconds": t_train, "photons": photons, "media": media}
            for integ in ["volpath", "guided"]:
                t, s = f[(integ, "equal-time")], f[(integ, "equal-spp")]
                mean = 100 * (float(t["mean"]) / float(t["mean_reference"]) - 1)
                train = f"{t_train:.2f} s" if integ == "guided" else ""
                md.append(f"| {name} | {integ} | {train} | {t['spp']} | {float(t['relmse']):.3g} | "
                          f"{float(t['mae']):.3g} | {mean:+.2f}% | {float(s['relmse']):.3g} | "
                          f"{float(s['seconds']):.2f} s |")
                case[integ] = {"equal_time": t, "equal_spp": s}
            et = float(f[("volpath", "equal-time")]["relmse"]) / float(f[("guided", "equal-time")]["relmse"])
            es = float(f[("volpath", "equal-spp")]["relmse"]) / float(f[("guided", "equal-spp")]["relmse"])
            case["ratio_equal_time"], case["ratio_equal_spp"] = et, es
            results["cases"][name] = case
        md.append("")
        for name, what, _, _ in cases:
            c = results["cases"][name]
            md.append(f"- **{name}** ({what}; {c['media']}): relMSE ratio {c['ratio_equal_time']:.2f}× at equal "
                      f"time, {c['ratio_equal_spp']:.2f}× at 64 spp; training {c['training_seconds']:.2f} s "
                      f"({100 * c['training_seconds'] / EQUAL_TIME:.0f} % of the budget). Images and error "
                      f"curves: [{name}/]({name}/results.md).")
        md.append("")

        # 1b. The candle at the 60-s budget: guided's default 4 rounds and 7 (a better
        # guide for 5 s more training), against a volpath reference of two
        # independent halves; the reference's own remaining noise, a quarter of the halves'
        # relMSE against each other, is taken out of each measured relMSE as well.
        halves = [long_reference(wax, seed) for seed in LONG_REF_SEEDS]
        parts = os.path.join(work, "long-ref-parts")
        os.makedirs(parts)
        for i, h in enumerate(halves):
            shutil.copy(h, os.path.join(parts, f"half{i}.exr"))
        long_ref = os.path.join(work, "wax-long-ref.exr")
        run(["merge", parts, "--output", long_ref])
        ref_noise = diff_relmse(halves[0], halves[1]) / 4.0
        out = os.path.join(HERE, "candle-60s")
        shutil.rmtree(out, ignore_errors=True)
        f = finals(compare(wax, long_ref, out, ["volpath", "guided"], time_s=LONG_TIME))
        seven = variant(wax, os.path.join(work, "wax-7-rounds.pbrt"), [guided('"integer trainingiterations" 7')])
        f7 = finals(compare(seven, long_ref, os.path.join(work, "candle-60s-7"), ["guided"], time_s=LONG_TIME,
                            keep_images=False))
        vp = float(f[("volpath", "equal-time")]["relmse"])
        long = {"volpath": f[("volpath", "equal-time")], "guided": f[("guided", "equal-time")],
                "guided_7_rounds": f7[("guided", "equal-time")], "reference_noise_relmse": ref_noise}
        results["candle_60s"] = long
        md += [f"## The candle at {LONG_TIME:.0f} s", "",
               f"Against a volpath reference of 2 × {LONG_REF_SPP} spp (seeds {LONG_REF_SEEDS[0]} and "
               f"{LONG_REF_SEEDS[1]}). Its own remaining noise, relMSE {ref_noise:.3g} (a quarter of the two "
               "halves' relMSE against each other), is in every measured relMSE; the last two columns take it "
               "out.", "",
               "| integrator | training | spp in time | relMSE | volpath : it | relMSE − reference noise | "
               "volpath : it |", "|---|---|--:|--:|--:|--:|--:|"]
        for key, label, train in [("volpath", "volpath", ""), ("guided", "guided", "4 rounds (default)"),
                                  ("guided_7_rounds", "guided", "7 rounds")]:
            r = long[key]
            e = float(r["relmse"])
            md.append(f"| {label} | {train} | {r['spp']} | {e:.3g} | {vp / e:.2f}× | {e - ref_noise:.3g} | "
                      f"{(vp - ref_noise) / (e - ref_noise):.2f}× |")
        md.append("")

        # 2. Fig. 16: g sweep, MIS vs RIS vs selective.
        gs = [0.0, 0.3, 0.5, 0.7, 0.85, 0.95]
        modes = [("MIS", '"float selectivethreshold" 2'), ("RIS", '"float selectivethreshold" 0'),
                 ("selective", "")]
        sweep = {}
        for g in gs:
            base = variant(wax, os.path.join(work, f"g{g}.pbrt"), [(r'"float g" \[ 0.85 \]', f'"float g" [ {g} ]')])
            ref = reference(base, os.path.join(work, f"g{g}-ref.exr"))
            rows = compare(base, ref, os.path.join(work, f"g{g}-vp"), ["volpath"], time_s=EQUAL_TIME,
                           keep_images=False)
            sweep.setdefault("volpath", []).append((g, float(finals(rows)[("volpath", "equal-time")]["relmse"])))
            for label, params in modes:
                sc = variant(base, os.path.join(work, f"g{g}-{label}.pbrt"), [guided(params)])
                rows = compare(sc, ref, os.path.join(work, f"g{g}-{label}"), ["guided"], time_s=EQUAL_TIME,
                               keep_images=False)
                sweep.setdefault(label, []).append((g, float(finals(rows)[("guided", "equal-time")]["relmse"])))
        results["fig16_g_sweep"] = sweep
        fig, ax = plt.subplots(figsize=(6, 4))
        for label, pts in sweep.items():
            ax.semilogy([p[0] for p in pts], [p[1] for p in pts], "o-", label=label)
        ax.set_xlabel("anisotropy g")
        ax.set_ylabel(f"relMSE at equal time ({EQUAL_TIME} s)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
        ax.set_title("MIS vs RIS vs selective (paper Fig. 16), milk in glass")
        fig.tight_layout()
        fig.savefig(os.path.join(HERE, "fig16-g-sweep.png"), dpi=110)
        plt.close(fig)
        md += ["## MIS vs RIS vs selective against g (paper Fig. 16)", "",
               "Milk in the glass sphere (wax-small-light with g varied), equal time.", "",
               "![g sweep](fig16-g-sweep.png)", "",
               "| method | " + " | ".join(f"g {g}" for g in gs) + " |", "|---|" + "--:|" * len(gs)]
        for label, pts in sweep.items():
            md.append(f"| {label} | " + " | ".join(f"{p[1]:.3g}" for p in pts) + " |")
        md.append("")

        # 3. Fig. 18: candidates.
        ms = [1, 2, 4, 6, 8, 16, 32]
        cand = {"equal spp (64)": [], f"equal time ({EQUAL_TIME} s)": []}
        for m in ms:
            sc = variant(wax, os.path.join(work, f"m{m}.pbrt"), [guided(f'"integer candidates" {m}')])
            rows = compare(sc, wax_ref, os.path.join(work, f"m{m}"), ["guided"], time_s=EQUAL_TIME, spp=64,
                           keep_images=False)
            f = finals(rows)
            cand["equal spp (64)"].append((m, float(f[("guided", "equal-spp")]["relmse"]),
                                           float(f[("guided", "equal-spp")]["seconds"])))
            cand[f"equal time ({EQUAL_TIME} s)"].append((m, float(f[("guided", "equal-time")]["relmse"]),
                                                         float(f[("guided", "equal-time")]["spp"])))
        results["fig18_candidates"] = cand
        fig, axes = plt.subplots(1, 2, figsize=(10, 4))
        for ax, (label, pts) in zip(axes, cand.items()):
            ax.semilogx([p[0] for p in pts], [p[1] for p in pts], "o-")
            ax.set_xscale("log", base=2)
            ax.set_xlabel("candidates M")
            ax.set_ylabel("relMSE")
            ax.set_title(label)
            ax.grid(True, which="both", alpha=0.3)
        fig.suptitle("Number of resampling candidates (paper Fig. 18), Candle case")
        fig.tight_layout()
        fig.savefig(os.path.join(HERE, "fig18-candidates.png"), dpi=110)
        plt.close(fig)
        md += ["## Candidates (paper Fig. 18)", "", "![candidates](fig18-candidates.png)", "",
               "| M | " + " | ".join(str(m) for m in ms) + " |", "|---|" + "--:|" * len(ms)]
        pts = cand["equal spp (64)"]
        md.append("| relMSE at 64 spp | " + " | ".join(f"{p[1]:.3g}" for p in pts) + " |")
        md.append("| seconds for 64 spp | " + " | ".join(f"{p[2]:.2f}" for p in pts) + " |")
        pts = cand[f"equal time ({EQUAL_TIME} s)"]
        md.append(f"| relMSE in {EQUAL_TIME} s | " + " | ".join(f"{p[1]:.3g}" for p in pts) + " |")
        md.append("")

        # 4. Fig. 19: training iterations, at equal spp.
        its = [1, 2, 3, 4, 5, 6]
        fig19 = []
        for k in its:
            sc = variant(wax, os.path.join(work, f"it{k}.pbrt"), [guided(f'"integer trainingiterations" {k}')])
            rows = compare(sc, wax_ref, os.path.join(work, f"it{k}"), ["guided"], spp=64, keep_images=False)
            t_train, photons, _ = training(sc, work)
            fig19.append((k, float(finals(rows)[("guided", "equal-spp")]["relmse"]), t_train, photons))
        results["fig19_iterations"] = fig19
        vp64 = float(results["cases"]["candle"]["volpath"]["equal_spp"]["relmse"])
        fig, ax = plt.subplots(figsize=(6, 4))
        ax.semilogy([p[0] for p in fig19], [p[1] for p in fig19], "o-", label="guided, 64 spp")
        ax.axhline(vp64, color="k", ls="--", lw=1, label="volpath, 64 spp")
        ax2 = ax.twinx()
        ax2.plot([p[0] for p in fig19], [p[2] for p in fig19], "s:", color="tab:orange", label="training (s)")
        ax2.set_ylabel("training seconds", color="tab:orange")
        ax.set_xlabel("training iterations")
        ax.set_ylabel("relMSE")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(loc="upper center")
        ax.set_title("Training iterations (paper Fig. 19), Candle case")
        fig.tight_layout()
        fig.savefig(os.path.join(HERE, "fig19-iterations.png"), dpi=110)
        plt.close(fig)
        md += ["## Training iterations (paper Fig. 19)", "",
               "Equal spp (64), so the rendering time is the same; the training time grows with the photons "
               "(`photons`·(2^k − 1)).", "", "![iterations](fig19-iterations.png)", "",
               "| iterations | " + " | ".join(str(k) for k in its) + " |", "|---|" + "--:|" * len(its),
               "| relMSE at 64 spp | " + " | ".join(f"{p[1]:.3g}" for p in fig19) + " |",
               "| training (s) | " + " | ".join(f"{p[2]:.2f}" for p in fig19) + " |",
               "| photons | " + " | ".join(str(p[3]) for p in fig19) + " |", ""]

        # 5. Fig. 20: rough glass.
        rough = []
        for r in [0.0, 0.01, 0.1, 0.5]:
            sc = variant(wax, os.path.join(work, f"r{r}.pbrt"),
                         [(r'"dielectric" "float eta" \[ 1.4 \]', f'"dielectric" "float eta" [ 1.4 ] "float roughness" [ {r} ]')])
            ref = wax_ref if r == 0.0 else reference(sc, os.path.join(work, f"r{r}-ref.exr"))
            rows = compare(sc, ref, os.path.join(work, f"r{r}"), ["volpath", "guided"], time_s=EQUAL_TIME,
                           keep_images=False)
            f = finals(rows)
            v, g = float(f[("volpath", "equal-time")]["relmse"]), float(f[("guided", "equal-time")]["relmse"])
            rough.append((r, v, g))
        results["fig20_roughness"] = rough
        fig, ax = plt.subplots(figsize=(6, 4))
        xs = range(len(rough))
        ax.bar([x - 0.2 for x in xs], [p[1] for p in rough], 0.4, label="volpath")
        ax.bar([x + 0.2 for x in xs], [p[2] for p in rough], 0.4, label="guided")
        ax.set_xticks(list(xs), [f"roughness {p[0]}" for p in rough])
        ax.set_yscale("log")
        ax.set_ylabel(f"relMSE at equal time ({EQUAL_TIME} s)")
        ax.legend()
        ax.set_title("Rough glass (paper Fig. 20), Candle case")
        fig.tight_layout()
        fig.savefig(os.path.join(HERE, "fig20-roughness.png"), dpi=110)
        plt.close(fig)
        md += ["## Rough glass (paper Fig. 20)", "", "![roughness](fig20-roughness.png)", "",
               "| roughness | volpath relMSE | guided relMSE | ratio |", "|--:|--:|--:|--:|"]
        for r, v, g in rough:
            md.append(f"| {r} | {v:.3g} | {g:.3g} | {v / g:.2f}× |")
        md.append("")

        # 6. Every pbrt-scenes scene at equal time.
        md += [f"## Every pbrt-scenes scene at equal time ({EQUAL_TIME} s)", "",
               "| scene | guided media | volpath relMSE | guided relMSE | ratio |", "|---|---|--:|--:|--:|"]
        allscenes = {}
        for s in sorted(f[:-5] for f in os.listdir(SCENES) if f.endswith(".pbrt") and f != "default.pbrt"):
            scene = os.path.join(SCENES, s + ".pbrt")
            rows = compare(scene, os.path.join(REFS, s + ".exr"), os.path.join(work, "all-" + s),
                           ["volpath", "guided"], time_s=EQUAL_TIME, keep_images=False)
            f = finals(rows)
            v, g = float(f[("volpath", "equal-time")]["relmse"]), float(f[("guided", "equal-time")]["relmse"])
            media = training(scene, work)[2]
            allscenes[s] = {"volpath": v, "guided": g, "ratio": v / g, "media": media}
            md.append(f"| {s} | {media} | {v:.3g} | {g:.3g} | {v / g:.2f}× |")
        results["all_scenes"] = allscenes
        md.append("")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    open(os.path.join(HERE, "results.md"), "w").write("\n".join(md) + "\n")
    json.dump(results, open(os.path.join(HERE, "results.json"), "w"), indent=1)


if __name__ == "__main__":
    main()
