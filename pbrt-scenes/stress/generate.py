#!/usr/bin/env python3
"""Writes the stress matrix of `nimbus stress` (issue 14): one small scene per condition, each
varying one thing of `00-base.pbrt`, plus the radiance graph's config beside each (`<stem>.json`,
read by `radiancegraph` as the thesis's graph_maker reads `scene.json`). Run from this directory:

    python3 generate.py

The sampler's `pixelsamples` is the spp of the VolPath reference `nimbus stress` renders (and
caches here); the cells themselves render at equal time. Deterministic: the same files every run.
"""

# The base: a homogeneous sphere (radius 1, optical radius 4, albedo 0.9, isotropic, gray)
# behind an `interface` boundary, lit by a distant sun from the upper left; nothing else. It
# meets every assumption of every method (the radiance graph's included), so each condition
# below breaks one.
BASE = dict(
    sigma_t=4.0,
    albedo=0.9,
    chroma=(1.0, 1.0, 1.0),
    g=0.0,
    le=None,
    lights=["sun"],
    boundary='Material "interface"',
    radius_modifier=20.0,
    spp=16384,
)

LIGHTS = {
    "sun": 'LightSource "distant" "point3 from" [-1 1.5 1] "point3 to" [0 0 0] "rgb L" [3 3 3]',
    "sky": 'LightSource "infinite" "rgb L" [0.15 0.2 0.3]',
    # The same power at the same place, ever smaller: a sphere of radius 1, 0.05, and a point.
    "area": 'AttributeBegin\n  Translate -2 2.5 2\n  AreaLightSource "diffuse" "rgb L" [1.5 1.5 1.5]\n'
    '  Shape "sphere" "float radius" 1\nAttributeEnd',
    "small": 'AttributeBegin\n  Translate -2 2.5 2\n  AreaLightSource "diffuse" "rgb L" [600 600 600]\n'
    '  Shape "sphere" "float radius" 0.05\nAttributeEnd',
    "point": 'LightSource "point" "point3 from" [-2 2.5 2] "rgb I" [4.71 4.71 4.71]',
    "inner": 'LightSource "point" "point3 from" [0.3 -0.2 0.2] "rgb I" [1 1 1]',
}

# (file stem, what varies, changes to BASE). The order is the heat map's.
CONDITIONS = [
    ("00-base", "base: albedo 0.9, isotropic, optical radius 4, gray, distant sun, interface boundary", {}),
    ("01-albedo-0.5", "albedo 0.5", dict(albedo=0.5)),
    ("02-albedo-0.999", "albedo 0.999 (long scattering chains)", dict(albedo=0.999)),
    ("03-g-neg0.5", "anisotropy g = -0.5 (back scattering)", dict(g=-0.5)),
    ("04-g-0.95", "anisotropy g = 0.95 (strongly forward)", dict(g=0.95)),
    ("05-thin-0.1", "optical radius 0.1 (thin haze)", dict(sigma_t=0.1)),
    ("06-thick-100", "optical radius 100 (dense)", dict(sigma_t=100.0)),
    ("07-light-area", "a sphere light of radius 1 instead of the sun", dict(lights=["area"])),
    ("08-light-small", "a sphere light of radius 0.05, same power", dict(lights=["small"])),
    ("09-light-point", "a point light, same power", dict(lights=["point"])),
    ("10-sun-sky", "sun and a blue sky", dict(lights=["sun", "sky"])),
    ("11-sun-sky-inner", "sun, sky and a point light inside the medium", dict(lights=["sun", "sky", "inner"])),
    ("12-chromatic", "chromatic extinction (sigma_t 2, 4, 8 in R, G, B)", dict(chroma=(0.5, 1.0, 2.0))),
    ("13-emissive", "an emitting medium (Le orange)", dict(le=(0.6, 0.3, 0.1))),
    # The boundary conditions keep 10-sun-sky's lights: through a smooth boundary no path
    # reaches a distant light alone (a delta direction behind a delta refraction), and the
    # picture would be black for every method.
    ("14-dielectric", "sun and sky as 10-sun-sky, a smooth dielectric boundary (eta 1.33)",
     dict(lights=["sun", "sky"], boundary='Material "dielectric" "float eta" 1.33')),
    ("15-rough-0.1", "sun and sky as 10-sun-sky, a rough dielectric boundary (roughness 0.1)",
     dict(lights=["sun", "sky"], boundary='Material "dielectric" "float eta" 1.33 "float roughness" 0.1')),
    ("16-rough-0.5", "sun and sky as 10-sun-sky, a rough dielectric boundary (roughness 0.5)",
     dict(lights=["sun", "sky"], boundary='Material "dielectric" "float eta" 1.33 "float roughness" 0.5')),
    ("17-nodes-0.5x", "graph nodes half the base's radius relative to the volume (radiusModifier 10)",
     dict(radius_modifier=10.0)),
    ("18-nodes-4x", "graph nodes 4x the base's radius relative to the volume (radiusModifier 80)",
     dict(radius_modifier=80.0)),
]


def rgb(v):
    return "[%s]" % " ".join("%g" % round(x, 6) for x in v)


def scene(stem, what, c):
    sigma_t = [c["sigma_t"] * k for k in c["chroma"]]
    sigma_s = [c["albedo"] * s for s in sigma_t]
    sigma_a = [s - a for s, a in zip(sigma_t, sigma_s)]
    le = ' "rgb Le" %s "float Lescale" 1' % rgb(c["le"]) if c["le"] else ""
    lights = "\n".join(LIGHTS[name] for name in c["lights"])
    return f"""# nimbus stress matrix (issue 14), condition {stem}: {what}.
# Written by generate.py; every condition varies one thing of 00-base.pbrt. The sampler's spp
# is the VolPath reference's; `nimbus stress` renders every integrator at equal time.
LookAt 0 0 4.5  0 0 0  0 1 0
Camera "perspective" "float fov" 32
Sampler "zsobol" "integer pixelsamples" {c["spp"]}
Integrator "volpath" "integer maxdepth" 1000
Film "rgb" "integer xresolution" 48 "integer yresolution" 48 "string filename" "{stem}.exr"
MakeNamedMedium "m" "string type" "homogeneous"
  "rgb sigma_a" {rgb(sigma_a)} "rgb sigma_s" {rgb(sigma_s)} "float g" {c["g"]}{le}
WorldBegin
{lights}
AttributeBegin
  MediumInterface "m" ""
  {c["boundary"]}
  Shape "sphere" "float radius" 1
AttributeEnd
"""


def config(c):
    # The thesis's defaults but the node radius, the number of light paths and a depth that
    # lets high-albedo paths finish: its default radius (diameter / 1000) and 400 x 400 x 100
    # paths build tens of millions of nodes in minutes here; these build in well under a second.
    return (
        '{\n  "graphBuilder": {"radiusModifier": %g, "dimensionSteps": 200, "iterationsPerStep": 10, '
        '"maxDepth": 100},\n'
        '  "lightingCalculator": {"bounces": [100]}\n}\n' % c["radius_modifier"]
    )


def main():
    for stem, what, changes in CONDITIONS:
        c = dict(BASE, **changes)
        with open(stem + ".pbrt", "w") as f:
            f.write(scene(stem, what, c))
        with open(stem + ".json", "w") as f:
            f.write(config(c))


if __name__ == "__main__":
    main()
