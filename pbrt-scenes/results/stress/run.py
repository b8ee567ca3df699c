#!/usr/bin/env python3
"""Regenerates pbrt-scenes/results/stress/ (issue 14's stress matrix).

Run from the repository root after `cargo build --release`, on an otherwise idle machine (the
cells are equal-time renders on all cores):

    python3 pbrt-scenes/results/stress/run.py [seconds per cell, default 2]

1. `python3 pbrt-scenes/stress/generate.py` writes the condition scenes (deterministic).
2. `nimbus stress` renders every integrator on every condition at equal time against the
   VolPath references cached in pbrt-scenes/stress/ (rendered there first if missing or stale:
   16384 spp each, about 40 s per condition on 2 cores) and writes stress.csv, stress.md and
   heatmap.svg/png here; the cells' images and logs go to cells/ (not committed).
3. cells.png: every cell's image beside the reference, a row per condition (sRGB, 2x).

STABILITY.md beside this script is written by hand from these results.
"""

import os
import subprocess
import sys

from PIL import Image, ImageDraw

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", "..", ".."))
# $NIMBUS names another binary (a copy, so that a build does not change it mid-run).
NIMBUS = os.environ.get("NIMBUS", os.path.join(ROOT, "target", "release", "nimbus"))
SCENES = os.path.join(ROOT, "pbrt-scenes", "stress")
SCALE = 2


def png_of(exr):
    png = exr[: -len(".exr")] + ".png"
    subprocess.run([NIMBUS, "convert", exr, png], check=True, capture_output=True)
    return Image.open(png).convert("RGB")


def contact_sheet(integrators):
    conditions = sorted(f[: -len(".pbrt")] for f in os.listdir(SCENES) if f.endswith(".pbrt"))
    columns = ["reference"] + integrators
    cell = 48 * SCALE
    label_w, head_h, pad = 150, 24, 4
    sheet = Image.new(
        "RGB",
        (label_w + len(columns) * (cell + pad), head_h + len(conditions) * (cell + pad)),
        "white",
    )
    draw = ImageDraw.Draw(sheet)
    for j, name in enumerate(columns):
        draw.text((label_w + j * (cell + pad) + 4, 6), name, fill="black")
    for i, cond in enumerate(conditions):
        y = head_h + i * (cell + pad)
        draw.text((4, y + cell // 2 - 6), cond, fill="black")
        refs = [f for f in os.listdir(SCENES) if f.startswith(cond + ".volpath-") and f.endswith(".exr")]
        for j, name in enumerate(columns):
            exr = (
                os.path.join(SCENES, refs[0])
                if name == "reference" and refs
                else os.path.join(HERE, "cells", cond, name + ".exr")
            )
            x = label_w + j * (cell + pad)
            if not os.path.exists(exr):
                draw.rectangle([x, y, x + cell - 1, y + cell - 1], fill=(215, 215, 215))
                draw.text((x + 8, y + cell // 2 - 6), "refused", fill=(80, 80, 80))
                continue
            img = png_of(exr)
            if name == "reference":
                os.remove(exr[: -len(".exr")] + ".png")
            sheet.paste(img.resize((cell, cell), Image.NEAREST), (x, y))
    sheet.save(os.path.join(HERE, "cells.png"))


def main():
    seconds = sys.argv[1] if len(sys.argv) > 1 else "2"
    subprocess.run([sys.executable, "generate.py"], cwd=SCENES, check=True)
    integrators = ["volpath", "simplevolpath", "radiancegraph", "pathgraph", "guided"]
    run = subprocess.run(
        [NIMBUS, "stress", "--scenes", SCENES, "--time", seconds, "--out", HERE,
         "--integrators", ",".join(integrators)],
        cwd=ROOT,
    )
    contact_sheet(integrators)
    # A failed cell is a finding, recorded in stress.md: say so, but keep the outputs.
    if run.returncode != 0:
        print("nimbus stress reported failed cells: see stress.md", file=sys.stderr)
    sys.exit(run.returncode)


if __name__ == "__main__":
    main()
