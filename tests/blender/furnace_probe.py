#!/usr/bin/env python3
"""Dev tool for blender_scripts/furnace_main.py (plain CPython, stdlib only).

Assembles a furnace script the way the gloffuse binary does (header +
groups_lib.py + furnace_main.py), runs it in a Blender, and reads the EXR
back to print per-sphere statistics, so the Blender side can be checked
without the Rust side.

  furnace_probe.py params --preset check --samples 64 --output /tmp/f/check.exr > p.json
  furnace_probe.py assemble p.json -o /tmp/f/furnace.py
  furnace_probe.py run p.json --blender blender            # Debian 3.4 binary
  furnace_probe.py run p.json --blender /opt/bpy45/bin/python
  furnace_probe.py stats p.json [EXR]                       # EXR defaults to furnace.output
  furnace_probe.py compare p.json A.exr B.exr [C.exr ...]   # seeds -> SE of the means

Sphere specs for `params --sphere`: plain:DIST:R (DIST one of BECKMANN, GGX,
ASHIKHMIN_SHIRLEY, MULTI_GGX) or group:DIST:R (the "Gloffuse (DIST)" shader
group; a matching "groups" entry with a rough test curve is added, unless
--base supplies real generate fields).

Statistics per cell: mean = sum(RGB)/3 / sum(alpha) over the cell (the
statistic the Rust side uses), centre = mean of the pixels with view cosine
>= 0.995 (a disc of radius 0.1 R), se = the standard error of the mean
estimated from the spread of fully covered pixels within 1-pixel-wide rings
of equal view cosine, as if pixels were independent. It is only a guide:
4.5/5.0's blue-noise sampling makes it pessimistic, while at 16 spp in 3.4
the seed-to-seed spread (`compare`) came out up to 2x larger. Trust `compare`.
"""

import argparse
import array
import json
import math
import os
import resource
import struct
import subprocess
import sys
import tempfile
import time
import zlib

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPTS = os.path.join(REPO, "blender_scripts")
DISTRIBUTIONS = ("BECKMANN", "GGX", "ASHIKHMIN_SHIRLEY")
PLAIN_DISTRIBUTIONS = DISTRIBUTIONS + ("MULTI_GGX",)
RESULT_PREFIX = "GLOFFUSE_RESULT "
# "centre" averages the pixels whose view cosine is at least this (a disc of
# radius 0.1 R, about 26 pixels at cell 64): E(mu) is flat there, and one
# pixel alone is too noisy to compare with DESIGN.md's 256-spp centre values.
CENTRE_MU = 0.995


# --- parameter documents -------------------------------------------------------

# Rough linear-space test curves f(r) = 100 + b r^2 + a r^3 (percent), fitted by
# hand to the sphere means E_avg(0.5) and E_avg(1) of Blender 4.5; only for
# exercising the groups (use --base for real coefficients).
TEST_CURVES = {"BECKMANN": [100.0, 0.0, -3.8, -29.6], "GGX": [100.0, 0.0, -36.9, -22.2],
               "ASHIKHMIN_SHIRLEY": [100.0, 0.0, -54.0, -22.0]}


def group_spec(distribution):
    names = {"BECKMANN": "Beckmann", "GGX": "GGX", "ASHIKHMIN_SHIRLEY": "Ashikhmin-Shirley"}
    return {"distribution": distribution,
            "correction_group": "Gloffuse correction (%s)" % names[distribution],
            "shader_group": "Gloffuse (%s)" % names[distribution],
            "curve": {"variable": "roughness", "numerator": TEST_CURVES[distribution],
                      "denominator": [1.0]}}


def parse_sphere(text):
    try:
        shader, distribution, roughness = text.split(":")
        roughness = float(roughness)
    except ValueError:
        raise SystemExit("bad sphere spec %r (want plain:DIST:R or group:DIST:R)" % text)
    if shader == "plain" and distribution in PLAIN_DISTRIBUTIONS:
        return {"shader": "plain", "distribution": distribution, "roughness": roughness}
    if shader == "group" and distribution in DISTRIBUTIONS:
        return {"shader": "group", "group": group_spec(distribution)["shader_group"],
                "roughness": roughness}
    raise SystemExit("bad sphere spec %r" % text)


def preset_spheres(name):
    if name == "check":
        return [parse_sphere(s) for s in (
            "plain:GGX:0.5", "plain:GGX:1", "plain:BECKMANN:0.5", "plain:BECKMANN:1",
            "plain:ASHIKHMIN_SHIRLEY:1", "plain:MULTI_GGX:1")]
    if name == "sweep77":
        # 7 rows x 11 roughnesses 0, 0.1, ..., 1: four plain BSDFs and three groups.
        rows = (["plain:%s" % d for d in PLAIN_DISTRIBUTIONS]
                + ["group:%s" % d for d in DISTRIBUTIONS])
        return [parse_sphere("%s:%g" % (row, i / 10.0)) for row in rows for i in range(11)]
    raise SystemExit("unknown preset %r" % name)


def cmd_params(args):
    spheres = preset_spheres(args.preset) if args.preset else []
    spheres += [parse_sphere(s) for s in args.sphere]
    if not spheres:
        raise SystemExit("no spheres: give --preset or --sphere")
    document = {}
    if args.base:
        with open(args.base) as f:
            document = json.load(f)
    if "groups" not in document:
        used = sorted({s["group"] for s in spheres if s["shader"] == "group"})
        document["groups"] = [g for g in (group_spec(d) for d in DISTRIBUTIONS)
                              if g["shader_group"] in used]
    columns = args.columns or min(11, len(spheres))
    document["furnace"] = {
        "cell": args.cell, "columns": columns, "samples": args.samples, "seed": args.seed,
        "radius_fraction": args.radius_fraction, "output": os.path.abspath(args.output),
        "threads": args.threads, "spheres": spheres,
    }
    json.dump(document, sys.stdout, indent=1)
    sys.stdout.write("\n")


# --- assembly (mirrors the gloffuse binary) ----------------------------------------

def assemble(document, groups_lib):
    # serde_json leaves non-ASCII characters unescaped; so does ensure_ascii=False.
    inner = json.dumps(document, ensure_ascii=False, separators=(",", ":"))
    header = ("# Generated by gloffuse (furnace_probe.py, dev) -- do not edit\n"
              "GLOFFUSE_PARAMS = %s\n" % json.dumps(inner, ensure_ascii=False))
    parts = [header]
    for path in (groups_lib, os.path.join(SCRIPTS, "furnace_main.py")):
        with open(path, encoding="utf-8") as f:
            parts.append(f.read())
    return "\n".join(parts)


def default_groups_lib():
    real = os.path.join(SCRIPTS, "groups_lib.py")
    return real if os.path.exists(real) else "/tmp/groups_lib_standin.py"


def load_params(path):
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def cmd_assemble(args):
    text = assemble(load_params(args.params), args.groups_lib or default_groups_lib())
    with open(args.out, "w", encoding="utf-8") as f:
        f.write(text)
    print(args.out)


def blender_command(blender, script):
    """`blender ...` binaries get the headless flags; anything else is a python with bpy."""
    if os.path.basename(blender).startswith("blender"):
        return [blender, "-b", "--factory-startup", "-noaudio", "--python-exit-code", "1",
                "--python", script, "--"]
    return [blender, script]


def cmd_run(args):
    document = load_params(args.params)
    groups_lib = args.groups_lib or default_groups_lib()
    workdir = tempfile.mkdtemp(prefix="furnace_probe_")
    script = os.path.join(workdir, "furnace.py")
    with open(script, "w", encoding="utf-8") as f:
        f.write(assemble(document, groups_lib))
    command = blender_command(args.blender, script)
    print("# groups_lib: %s" % groups_lib)
    print("# command: %s" % " ".join(command))
    start = time.perf_counter()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    log = os.path.join(workdir, "blender.log")
    with open(log, "w", encoding="utf-8") as f:
        f.write(proc.stdout)
    results = [line[len(RESULT_PREFIX):] for line in proc.stdout.splitlines()
               if line.startswith(RESULT_PREFIX)]
    print("# exit code %d, wall %.2f s, cpu %.2f s, log %s" % (proc.returncode, wall, cpu, log))
    if proc.returncode != 0 or len(results) != 1:
        sys.stdout.write(proc.stdout[-4000:])
        raise SystemExit("furnace run failed")
    result = json.loads(results[0])
    print("# result: %s" % json.dumps(result))
    if not args.keep:
        os.remove(script)
    if not args.no_stats:
        print_stats(document, result["output"])


# --- OpenEXR reading (scanline, single part, NONE/ZIPS/ZIP, HALF/FLOAT) ---------

def read_exr(path):
    """Return (width, height, {channel: array of floats, row-major, top row first})."""
    with open(path, "rb") as f:
        data = f.read()
    magic, version = struct.unpack_from("<iI", data, 0)
    if magic != 20000630:
        raise ValueError("%s is not an OpenEXR file" % path)
    if version & 0x1a00:  # tiled, deep, multi-part (0x400 = long names is fine)
        raise ValueError("%s: tiled, deep or multi-part EXR is not supported" % path)
    pos, header = 8, {}
    while data[pos] != 0:
        end = data.index(b"\0", pos)
        name = data[pos:end].decode()
        end2 = data.index(b"\0", end + 1)
        kind = data[end + 1:end2].decode()
        size, = struct.unpack_from("<i", data, end2 + 1)
        header[name] = (kind, data[end2 + 5:end2 + 5 + size])
        pos = end2 + 5 + size
    pos += 1
    channels, raw = [], header["channels"][1]
    p = 0
    while raw[p] != 0:
        end = raw.index(b"\0", p)
        pixel_type, = struct.unpack_from("<i", raw, end + 1)
        channels.append((raw[p:end].decode(), pixel_type))
        p = end + 17
    compression = header["compression"][1][0]
    xmin, ymin, xmax, ymax = struct.unpack("<4i", header["dataWindow"][1])
    width, height = xmax - xmin + 1, ymax - ymin + 1
    lines = {0: 1, 2: 1, 3: 16}.get(compression)
    if lines is None:
        raise ValueError("%s: compression %d is not supported (want NONE, ZIPS or ZIP)"
                         % (path, compression))
    chunks = (height + lines - 1) // lines
    offsets = struct.unpack_from("<%dQ" % chunks, data, pos)
    out = {name: array.array("f", bytes(4 * width * height)) for name, _ in channels}
    for offset in offsets:
        y, size = struct.unpack_from("<ii", data, offset)
        block = data[offset + 8:offset + 8 + size]
        n = min(lines, ymax + 1 - y)
        expected = n * width * sum(2 if t == 1 else 4 for _, t in channels)
        if compression != 0 and size < expected:
            block = undo_zip(zlib.decompress(block))
        p = 0
        for line in range(n):
            row = (y - ymin + line) * width
            for name, pixel_type in channels:
                if pixel_type == 1:
                    values = struct.unpack_from("<%de" % width, block, p)
                    p += 2 * width
                else:
                    values = array.array("f" if pixel_type == 2 else "I")
                    values.frombytes(block[p:p + 4 * width])
                    if sys.byteorder != "little":
                        values.byteswap()
                    p += 4 * width
                out[name][row:row + width] = array.array("f", values)
    return width, height, out


def undo_zip(t):
    """Undo OpenEXR's ZIP predictor and byte-interleaving."""
    t = bytearray(t)
    for i in range(1, len(t)):
        t[i] = (t[i - 1] + t[i] - 128) & 0xff
    half = (len(t) + 1) // 2
    out = bytearray(len(t))
    out[0::2] = t[:half]
    out[1::2] = t[half:]
    return bytes(out)


# --- statistics -------------------------------------------------------------------

def sphere_label(sphere):
    if sphere["shader"] == "plain":
        return "plain %s" % sphere["distribution"]
    return sphere["group"]


def cell_stats(exr, furnace, index):
    width, height, ch = exr
    cell, columns = furnace["cell"], furnace["columns"]
    x0, y0 = (index % columns) * cell, (index // columns) * cell
    radius = 0.5 * furnace["radius_fraction"] * cell
    centre = 0.5 * cell
    r, g, b, a = ch["R"], ch["G"], ch["B"], ch["A"]
    sum_rgb = sum_a = 0.0
    rings = {}
    centre_values = []
    centre_radius = radius * math.sqrt(1.0 - CENTRE_MU ** 2)
    for y in range(cell):
        row = (y0 + y) * width + x0
        for x in range(cell):
            i = row + x
            v = (r[i] + g[i] + b[i]) / 3.0
            sum_rgb += v
            sum_a += a[i]
            d = math.hypot(x + 0.5 - centre, y + 0.5 - centre)
            if d <= centre_radius and a[i] > 0:
                centre_values.append(v / a[i])
            if a[i] > 0.9999 and d < radius - 1.5:
                rings.setdefault(int(d), []).append(v)
    mean = sum_rgb / sum_a if sum_a > 0 else float("nan")
    # Per-pixel noise variance within each ring of (nearly) equal view cosine.
    var_sum, n_interior = 0.0, 0
    for values in rings.values():
        n = len(values)
        if n < 4:
            continue
        m = sum(values) / n
        var_sum += sum((v - m) ** 2 for v in values) / (n - 1) * n
        n_interior += n
    # Scale to all covered pixels (edge pixels assumed as noisy as the interior).
    se = math.sqrt(var_sum * sum_a / n_interior) / sum_a if n_interior else float("nan")
    return {"mean": mean, "centre": sum(centre_values) / len(centre_values),
            "se": se, "coverage": sum_a}


def print_stats(document, path):
    furnace = document["furnace"]
    exr = read_exr(path)
    width, height, ch = exr
    print("# %s: %d x %d, channels %s" % (path, width, height, ",".join(sorted(ch))))
    print("%4s  %-28s %5s %9s %9s %9s %7s %9s" % ("cell", "shader", "r", "mean", "centre", "se",
                                                  "se %", "coverage"))
    worst = 0.0
    for index, sphere in enumerate(furnace["spheres"]):
        s = cell_stats(exr, furnace, index)
        rel = 100.0 * s["se"] / s["mean"] if s["mean"] > 0 else float("nan")
        worst = max(worst, rel)
        print("%4d  %-28s %5.2f %9.5f %9.5f %9.6f %7.3f %9.1f" % (
            index, sphere_label(sphere), sphere["roughness"], s["mean"], s["centre"], s["se"],
            rel, s["coverage"]))
    print("# worst relative SE (ring estimate): %.3f %%" % worst)


def cmd_stats(args):
    document = load_params(args.params)
    print_stats(document, args.exr or document["furnace"]["output"])


def cmd_compare(args):
    """Renders of the same grid with different seeds: per sphere, the spread
    of the means across renders is the SE of one render's mean; printed next
    to the ring estimate (averaged over the renders)."""
    furnace = load_params(args.params)["furnace"]
    if len(args.exr) < 2:
        raise SystemExit("compare needs at least two EXRs")
    exrs = [read_exr(path) for path in args.exr]
    n = len(exrs)
    print("# %d renders; se seeds = std of the %d means; se ring = mean ring estimate" % (n, n))
    print("%4s  %-28s %5s %9s %10s %10s %8s %8s" % ("cell", "shader", "r", "mean", "se seeds",
                                                   "se ring", "seeds %", "ring %"))
    rel_sq, worst_seeds, worst_ring = [], (0.0, ""), (0.0, "")
    for index, sphere in enumerate(furnace["spheres"]):
        stats = [cell_stats(exr, furnace, index) for exr in exrs]
        means = [st["mean"] for st in stats]
        mean = sum(means) / n
        se_seeds = math.sqrt(sum((m - mean) ** 2 for m in means) / (n - 1))
        se_ring = sum(st["se"] for st in stats) / n
        rel_seeds = 100.0 * se_seeds / mean if mean > 0 else 0.0
        rel_ring = 100.0 * se_ring / mean if mean > 0 else 0.0
        rel_sq.append(rel_seeds ** 2)
        label = "%s r=%g" % (sphere_label(sphere), sphere["roughness"])
        worst_seeds = max(worst_seeds, (rel_seeds, label))
        worst_ring = max(worst_ring, (rel_ring, label))
        print("%4d  %-28s %5.2f %9.5f %10.6f %10.6f %8.3f %8.3f" % (
            index, sphere_label(sphere), sphere["roughness"], mean, se_seeds, se_ring,
            rel_seeds, rel_ring))
    print("# relative SE of one render's sphere mean: seeds RMS %.3f %%, worst %.3f %% (%s); "
          "ring worst %.3f %% (%s)" % (math.sqrt(sum(rel_sq) / len(rel_sq)), worst_seeds[0],
                                       worst_seeds[1], worst_ring[0], worst_ring[1]))


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("params", help="write a furnace parameter document to stdout")
    p.add_argument("--preset", choices=("check", "sweep77"))
    p.add_argument("--sphere", action="append", default=[], help="plain:DIST:R or group:DIST:R")
    p.add_argument("--base", help="JSON document with the generate fields to extend")
    p.add_argument("--cell", type=int, default=64)
    p.add_argument("--columns", type=int)
    p.add_argument("--samples", type=int, default=16)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--radius-fraction", type=float, default=0.9)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--output", required=True)
    p.set_defaults(func=cmd_params)

    p = sub.add_parser("assemble", help="write the generated furnace script")
    p.add_argument("params")
    p.add_argument("-o", "--out", required=True)
    p.add_argument("--groups-lib", help="default: blender_scripts/groups_lib.py, else the stand-in")
    p.set_defaults(func=cmd_assemble)

    p = sub.add_parser("run", help="assemble, run in a Blender, print per-sphere statistics")
    p.add_argument("params")
    p.add_argument("--blender", default="blender",
                   help="a blender binary, or a python that can import bpy")
    p.add_argument("--groups-lib")
    p.add_argument("--keep", action="store_true", help="keep the assembled script")
    p.add_argument("--no-stats", action="store_true")
    p.set_defaults(func=cmd_run)

    p = sub.add_parser("stats", help="per-sphere statistics of a furnace EXR")
    p.add_argument("params")
    p.add_argument("exr", nargs="?")
    p.set_defaults(func=cmd_stats)

    p = sub.add_parser("compare", help="SE of the sphere means from renders with different seeds")
    p.add_argument("params")
    p.add_argument("exr", nargs="+")
    p.set_defaults(func=cmd_compare)

    args = parser.parse_args()
    args.func(args)


if __name__ == "__main__":
    main()
