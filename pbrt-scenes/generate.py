#!/usr/bin/env python3
"""Writes the procedural parts of nimbus's scene suite: density grids (value noise, fixed
seed) and a small equal-area octahedral sky image. Run from this directory:

    python3 generate.py

Deterministic: the same files every run.
"""
import math
import random
import struct
import zlib


def value_noise(n, seed, octaves=4):
    rnd = random.Random(seed)
    lattice = {}

    def lat(i, j, k):
        key = (i, j, k)
        if key not in lattice:
            lattice[key] = rnd.random()
        return lattice[key]

    def smooth(t):
        return t * t * (3 - 2 * t)

    def noise(x, y, z):
        i, j, k = int(math.floor(x)), int(math.floor(y)), int(math.floor(z))
        fx, fy, fz = smooth(x - i), smooth(y - j), smooth(z - k)
        v = 0.0
        for dz in (0, 1):
            for dy in (0, 1):
                for dx in (0, 1):
                    w = (fx if dx else 1 - fx) * (fy if dy else 1 - fy) * (fz if dz else 1 - fz)
                    v += w * lat(i + dx, j + dy, k + dz)
        return v

    out = []
    for z in range(n):
        for y in range(n):
            for x in range(n):
                p = [(x + 0.5) / n, (y + 0.5) / n, (z + 0.5) / n]
                f, amp, s = 3.0, 0.5, 0.0
                for _ in range(octaves):
                    s += amp * noise(p[0] * f, p[1] * f, p[2] * f)
                    f *= 2.0
                    amp *= 0.5
                out.append(s)
    return out


def cloud_density(n, seed, squash=1.0):
    noise = value_noise(n, seed)
    out = []
    idx = 0
    for z in range(n):
        for y in range(n):
            for x in range(n):
                p = [(x + 0.5) / n - 0.5, ((y + 0.5) / n - 0.5) * squash, (z + 0.5) / n - 0.5]
                r = math.sqrt(p[0] ** 2 + p[1] ** 2 + p[2] ** 2)
                d = max(0.0, (0.42 - r) * 6.0 + (noise[idx] - 0.45) * 2.5)
                out.append(min(d, 1.5))
                idx += 1
    return out


def fmt(values, per_line=16):
    lines = []
    for i in range(0, len(values), per_line):
        lines.append("    " + " ".join("%.4g" % v for v in values[i : i + per_line]))
    return "\n".join(lines)


CUBE = """  Material "interface"
  Shape "trianglemesh" "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7  0 1 5 0 5 4  3 7 6 3 6 2  0 4 7 0 7 3  1 2 6 1 6 5 ]
    "point3 P" [ 0 0 0  1 0 0  1 1 0  0 1 0  0 0 1  1 0 1  1 1 1  0 1 1 ]"""


def write_cloud_sun_sky():
    n = 32
    d = cloud_density(n, 11, squash=1.4)
    with open("cloud-sun-sky.pbrt", "w") as f:
        f.write(f"""# Heterogeneous high-albedo cloud (32^3 uniformgrid, albedo 0.995, g = 0.7) under a sun and a blue sky.
# Tests: many-bounce forward scattering lit by a distant light and an environment.
LookAt 0 0.35 3.6  0 0 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Sampler "zsobol" "integer pixelsamples" [ 64 ]
Film "rgb" "integer xresolution" [ 128 ] "integer yresolution" [ 96 ] "string filename" [ "cloud-sun-sky.exr" ]
Integrator "volpath" "integer maxdepth" [ 64 ]
WorldBegin
LightSource "distant" "point3 from" [ 2 3 1 ] "point3 to" [ 0 0 0 ] "rgb L" [ 3.0 2.9 2.7 ]
LightSource "infinite" "rgb L" [ 0.12 0.18 0.32 ]
AttributeBegin
  Translate -1 -1 -1
  Scale 2 2 2
  MakeNamedMedium "cloud" "string type" [ "uniformgrid" ] "integer nx" [ {n} ] "integer ny" [ {n} ] "integer nz" [ {n} ]
    "rgb sigma_a" [ 0.05 0.05 0.05 ] "rgb sigma_s" [ 9.95 9.95 9.95 ] "float g" [ 0.7 ]
    "float density" [
{fmt(d)}
    ]
  MediumInterface "cloud" ""
{CUBE}
AttributeEnd
""")


def write_graph_cloud():
    n = 24
    d = cloud_density(n, 23)
    with open("graph-constraints-cloud.pbrt", "w") as f:
        f.write(f"""# Cloud meeting the radiance-graph constraints: one distant light, isotropic, gray, non-emissive.
# Tests: the conditions radiance graphs are built for (24^3 uniformgrid, albedo 1, g = 0, maxdepth 12).
LookAt 2.8 0.8 2.2  0 0 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Sampler "zsobol" "integer pixelsamples" [ 64 ]
Film "rgb" "integer xresolution" [ 96 ] "integer yresolution" [ 96 ] "string filename" [ "graph-constraints-cloud.exr" ]
Integrator "volpath" "integer maxdepth" [ 12 ]
WorldBegin
LightSource "distant" "point3 from" [ -0.5 1 0.3 ] "point3 to" [ 0 0 0 ] "rgb L" [ 2.5 2.5 2.5 ]
AttributeBegin
  Translate -1 -1 -1
  Scale 2 2 2
  MakeNamedMedium "cloud" "string type" [ "uniformgrid" ] "integer nx" [ {n} ] "integer ny" [ {n} ] "integer nz" [ {n} ]
    "rgb sigma_a" [ 0 0 0 ] "rgb sigma_s" [ 8 8 8 ] "float g" [ 0 ]
    "float density" [
{fmt(d)}
    ]
  MediumInterface "cloud" ""
{CUBE}
AttributeEnd
""")


def write_emissive():
    n = 20
    d = cloud_density(n, 5)
    t = [max(0.0, 4.0 * v - 1.0) * 5.5 for v in d]
    with open("emissive-smoke.pbrt", "w") as f:
        f.write(f"""# Emissive grid: smoke glowing from a temperature grid (blackbody), dim sky, ground.
# Tests: medium emission (only found by tracking through the medium; no light sampling helps).
LookAt 0 0.4 3.8  0 -0.1 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Sampler "zsobol" "integer pixelsamples" [ 64 ]
Film "rgb" "integer xresolution" [ 112 ] "integer yresolution" [ 96 ] "string filename" [ "emissive-smoke.exr" ]
Integrator "volpath" "integer maxdepth" [ 24 ]
WorldBegin
LightSource "infinite" "rgb L" [ 0.04 0.045 0.06 ]
AttributeBegin
  Translate -1 -1 -1
  Scale 2 2 2
  MakeNamedMedium "smoke" "string type" [ "uniformgrid" ] "integer nx" [ {n} ] "integer ny" [ {n} ] "integer nz" [ {n} ]
    "rgb sigma_a" [ 1.5 1.5 1.5 ] "rgb sigma_s" [ 3 3 3 ] "float g" [ 0.2 ]
    "float temperaturescale" [ 100 ] "float temperatureoffset" [ 0 ]
    "float density" [
{fmt(d)}
    ]
    "float temperature" [
{fmt(t)}
    ]
  MediumInterface "smoke" ""
{CUBE}
AttributeEnd
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0.4 0.4 0.4 ]
  Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ] "point3 P" [ -8 -1.01 -8  8 -1.01 -8  8 -1.01 8  -8 -1.01 8 ]
AttributeEnd
""")


def write_many_lights():
    """A foggy street: 20 sphere lanterns, 20 lit windows (two triangles each) and 10
    spotlights, spread over 40 units: light sampling by power picks mostly lights far from the
    shading point; pbrt-v4's light BVH picks the near ones."""
    with open("many-lights.pbrt", "w") as f:
        f.write("""# Many lights: a street in light fog with 20 sphere lanterns, 20 lit windows (one-sided
# quads, two triangle lights each) and 10 downward spotlights spread over 40 units, 70
# lights in all: where pbrt-v4's light BVH beats sampling lights by power.
MakeNamedMedium "fog" "string type" [ "homogeneous" ] "rgb sigma_a" [ 0.01 0.01 0.01 ] "rgb sigma_s" [ 0.06 0.06 0.06 ] "float g" [ 0.3 ]
MediumInterface "fog" "fog"
LookAt 0 1.7 -1  0 1.5 20  0 1 0
Camera "perspective" "float fov" [ 50 ]
Sampler "zsobol" "integer pixelsamples" [ 64 ]
Film "rgb" "integer xresolution" [ 128 ] "integer yresolution" [ 80 ] "string filename" [ "many-lights.exr" ]
Integrator "volpath" "integer maxdepth" [ 8 ]
WorldBegin
AttributeBegin
  MediumInterface "fog" ""
  Material "interface"
  Shape "sphere" "float radius" [ 80 ]
AttributeEnd
Material "diffuse" "rgb reflectance" [ 0.45 0.45 0.45 ]
Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ] "point3 P" [ -4 0 -2  4 0 -2  4 0 44  -4 0 44 ]
Material "diffuse" "rgb reflectance" [ 0.5 0.42 0.35 ]
Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3  4 5 6 4 6 7 ]
  "point3 P" [ -4 0 -2  -4 0 44  -4 6 44  -4 6 -2   4 0 -2  4 6 -2  4 6 44  4 0 44 ]
""")
        warm = [(22, 14, 6), (18, 11, 5), (25, 17, 8)]
        cool = [(5, 7, 12), (6, 8, 10), (8, 8, 9)]
        for k in range(20):
            x = -3 if k % 2 == 0 else 3
            z = 1 + 2 * k
            L = warm[k % 3]
            f.write(f"""AttributeBegin
  Translate {x} 2.6 {z}
  AreaLightSource "diffuse" "rgb L" [ {L[0]} {L[1]} {L[2]} ]
  Material "diffuse" "rgb reflectance" [ 0 0 0 ]
  Shape "sphere" "float radius" [ 0.1 ]
AttributeEnd
""")
        for k in range(20):
            # Windows face the street: the left wall's towards +x, the right wall's towards -x.
            side = -1 if k % 2 == 0 else 1
            x = side * 3.99
            z0 = 2 + 2 * k
            L = cool[k % 3]
            quad = [(x, 1.2, z0), (x, 1.2, z0 + 0.8), (x, 2.0, z0 + 0.8), (x, 2.0, z0)]
            if side > 0:
                quad = quad[::-1]
            pts = "  ".join(f"{a} {b} {c}" for a, b, c in quad)
            f.write(f"""AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ {L[0]} {L[1]} {L[2]} ]
  Material "diffuse" "rgb reflectance" [ 0.1 0.1 0.1 ]
  Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ] "point3 P" [ {pts} ]
AttributeEnd
""")
        for k in range(10):
            z = 4 * k + 3
            f.write(f"""AttributeBegin
  LightSource "spot" "point3 from" [ 0 4 {z} ] "point3 to" [ 0 0 {z} ] "float coneangle" [ 35 ] "float conedeltaangle" [ 10 ] "rgb I" [ 6 6 5.5 ]
AttributeEnd
""")


def equal_area_square_to_sphere(u, v):
    u, v = 2 * u - 1, 2 * v - 1
    up, vp = abs(u), abs(v)
    sd = 1 - (up + vp)
    d = abs(sd)
    r = 1 - d
    phi = (1 if r == 0 else (vp - up) / r + 1) * math.pi / 4
    z = math.copysign(1 - r * r, sd)
    cphi = math.copysign(math.cos(phi), u)
    sphi = math.copysign(math.sin(phi), v)
    s = r * math.sqrt(max(0.0, 2 - r * r))
    return cphi * s, sphi * s, z


def write_sky_png(path, size=64):
    # A sky in pbrt-v4's light space (+z up): blue gradient, bright sun disc, dark ground.
    sun = (0.4, 0.3, 0.866)
    rows = []
    for j in range(size):
        row = bytearray([0])
        for i in range(size):
            x, y, z = equal_area_square_to_sphere((i + 0.5) / size, (j + 0.5) / size)
            if z < 0:
                rgb = (0.08, 0.07, 0.06)
            else:
                rgb = (0.25 + 0.2 * (1 - z), 0.4 + 0.2 * (1 - z), 0.85)
            cosang = x * sun[0] + y * sun[1] + z * sun[2]
            if cosang > 0.995:
                rgb = (1.0, 0.97, 0.9)
            for c in rgb:
                v = min(max(c, 0.0), 1.0)
                s = 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055
                row.append(int(s * 255 + 0.5))
        rows.append(bytes(row))
    raw = b"".join(rows)

    def chunk(tag, data):
        c = struct.pack(">I", len(data)) + tag + data
        return c + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


if __name__ == "__main__":
    write_cloud_sun_sky()
    write_graph_cloud()
    write_emissive()
    write_many_lights()
    write_sky_png("sky.png")
