"""Equal-noise benchmark of coif's Chiang hair lobe against Mitsuba 3's `hair` BSDF and Cycles'
Principled Hair BSDF (Chiang model), the same Chiang et al. 2016 model, on one groom and one shot
(`make bench-peers`; never part of `make test`).

Both renderers get the same curves: a coif-generated groom, read here from its `.hair` file, whose
polyline vertices become the control points of cubic B-splines, written to a `.usda` for coif and
handed to Mitsuba as a `bsplinecurve` (Embree round B-splines in both). Not `linearcurve`: in
Mitsuba 3.9.1 it sets no surface parameterisation, so the shading frame's tangent is an arbitrary
direction across the fibre and the `hair` BSDF scatters about the wrong axis (a back-lit fibre
shows 0.43x the transmission its own BSDF predicts; `bsplinecurve` agrees with coif within 0.4 %).
Cycles traces only Catmull-Rom curves: it gets Catmull-Rom curves through points of the same
B-splines (scripts/bench_peers_cycles.py, a bpy worker in .deps/bpy-venv that keeps the scene
loaded between renders; it prints how far its curves stray from the B-splines).
The same camera, a distant key light, a constant dome, the
same pigment and roughness, 8 scattering vertices, 2 threads. Each is measured against its own
high-spp reference (so bias between the two does not count, only noise): relative RMSE of
luminance on the full frame and in the dense-hair window (in coif's reference: the densest quarter of the covered pixels), at several sample counts, several seeds each. Time is render time only (coif's
`seconds` from `--json`, Mitsuba's `mi.render` to evaluated pixels after a warm-up that compiles
its kernels, Cycles' `bpy.ops.render.render` with persistent data after a warm-up render); scene
loading and BVH builds are left out of all three.

Time to equal noise: the error of each renderer is fitted as c / sqrt(spp) (Monte Carlo), its cost
as seconds per spp; the time to reach a target error e is (c / e)^2 x seconds-per-spp. The target
is coif's error at `--target-spp`. Figures on a shared machine are stretched by other jobs: the
load average is printed with them; compare the ratios, not the seconds.

Run with the Mitsuba venv's Python (scripts/peers_setup.sh makes it):
  .deps/mitsuba-venv/bin/python scripts/bench_peers.py --coif target/release/coif --out out/bench-peers
"""
import argparse
import json
import math
import os
import struct
import subprocess
import time

import numpy as np

# Dr.Jit's llvm backend needs an LLVM that selects `fminimum` (19, from scripts/peers_setup.sh).
os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")

# The shot, in coif's space (metres, Y up). The generated head is centred near the origin.
CAMERA = {"position": [0.32, 0.12, 0.62], "target": [0.0, 0.0, 0.0], "fov": 32.0}
KEY_DIRECTION = [-0.45, 0.75, 0.5]  # towards the light
KEY_IRRADIANCE = 2.5
DOME_RADIANCE = 0.25
EUMELANIN, PHEOMELANIN = 1.3, 0.0
BETA_M, BETA_N, ALPHA_DEGREES = 0.3, 0.3, 2.0
MAX_BOUNCES = 8
KEY_ANGLE_DEGREES = 0.53
HAIR_IOR = 1.55
# coif's and Mitsuba's (pbrt's) absorption per unit radius of one unit of each melanin.
EUMELANIN_SIGMA_A = np.array([0.419, 0.697, 1.37])
PHEOMELANIN_SIGMA_A = np.array([0.187, 0.4, 1.05])


def load():
    return os.getloadavg()


def read_hair(path):
    """Strands of a Cem Yuksel .hair file: a list of (points n x 3, radii n)."""
    data = open(path, "rb").read()
    strands, points, flags, default_segments = struct.unpack_from("<4I", data, 4)
    default_thickness = struct.unpack_from("<f", data, 20)[0]
    offset = 128
    if flags & 1:
        segments = np.frombuffer(data, "<u2", strands, offset).astype(int)
        offset += 2 * strands
    else:
        segments = np.full(strands, default_segments)
    xyz = np.frombuffer(data, "<f4", 3 * points, offset).reshape(points, 3)
    offset += 12 * points
    if flags & 4:
        thickness = np.frombuffer(data, "<f4", points, offset)
    else:
        thickness = np.full(points, default_thickness, dtype=np.float32)
    out, start = [], 0
    for s in segments:
        n = int(s) + 1
        out.append((xyz[start : start + n], 0.5 * thickness[start : start + n]))
        start += n
    assert start == points, "the .hair file's counts disagree"
    return out


def write_mitsuba_curves(strands, path):
    with open(path, "w") as f:
        for points, radii in strands:
            for p, r in zip(points, radii):
                f.write(f"{p[0]:.7g} {p[1]:.7g} {p[2]:.7g} {r:.7g}\n")
            f.write("\n")


def write_usda_bspline(strands, path):
    """The strands as one UsdGeom BasisCurves prim: cubic, B-spline, widths per vertex."""
    with open(path, "w") as f:
        f.write('#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = "Y"\n)\n\ndef BasisCurves "groom"\n{\n')
        f.write('    uniform token type = "cubic"\n    uniform token basis = "bspline"\n')
        f.write('    uniform token wrap = "nonperiodic"\n')
        f.write("    int[] curveVertexCounts = [" + ", ".join(str(len(p)) for p, _ in strands) + "]\n")
        points = ", ".join(f"({x:.7g}, {y:.7g}, {z:.7g})" for p, _ in strands for x, y, z in p)
        f.write(f"    point3f[] points = [{points}]\n")
        widths = ", ".join(f"{2 * r:.7g}" for _, radii in strands for r in radii)
        f.write(f'    float[] widths = [{widths}] (\n        interpolation = "vertex"\n    )\n}}\n')


def luminance(rgb):
    return 0.2126 * rgb[..., 0] + 0.7152 * rgb[..., 1] + 0.0722 * rgb[..., 2]


def relative_rmse(image, reference, mask=None):
    a, b = luminance(image), luminance(reference)
    if mask is not None:
        a, b = a[mask], b[mask]
    return float(np.sqrt(np.mean((a - b) ** 2)) / max(np.mean(b), 1e-12))


class Coif:
    name = "coif (Chiang)"

    def __init__(self, binary, groom, out, width, height):
        self.binary, self.groom, self.out = binary, groom, out
        self.width, self.height = width, height
        scene = os.path.join(out, "shot.toml")
        c = CAMERA
        with open(scene, "w") as f:
            f.write(f"[camera]\nposition = {c['position']}\ntarget = {c['target']}\nfov = {c['fov']}\n")
            f.write(
                f'[[lights]]\ntype = "distant"\ndirection = {KEY_DIRECTION}\nintensity = {KEY_IRRADIANCE}\n'
                f"angle = {KEY_ANGLE_DEGREES}\n"
            )
            f.write(f'[[lights]]\ntype = "dome"\nintensity = {DOME_RADIANCE}\n')
            f.write("[floor]\nenabled = false\n")
        self.scene = scene

    def render(self, spp, seed, aov=False):
        import mitsuba as mi

        path = os.path.join(self.out, f"coif_{spp}_{seed}.exr")
        args = [
            self.binary, "render", self.groom, "-o", path, "--scene", self.scene,
            "--res", f"{self.width}x{self.height}", "--spp", str(spp), "--seed", str(seed),
            "--lobe", "chiang", "--melanin", str(EUMELANIN), "--pheomelanin", str(PHEOMELANIN),
            "--roughness", str(BETA_M), "--azimuthal-roughness", str(BETA_N),
            "--cuticle-tilt", str(ALPHA_DEGREES), "--max-depth", str(MAX_BOUNCES),
            "--head", "off", "--threads", "2", "--json",
        ]  # fmt: skip
        result = subprocess.run(args, check=True, capture_output=True, text=True)
        stats = json.loads(result.stdout)
        seconds = stats.get("seconds") or stats.get("stats", {}).get("seconds")
        pixels = np.array(mi.Bitmap(path), dtype=np.float64)
        os.remove(path)
        return pixels[..., :3], pixels[..., 3], float(seconds)


class Mitsuba:
    name = "Mitsuba 3 (hair, llvm_ad_rgb)"

    def __init__(self, strands, out, width, height):
        import drjit as dr
        import mitsuba as mi

        mi.set_variant("llvm_ad_rgb")
        dr.set_thread_count(2)
        curves = os.path.join(out, "groom_mitsuba.txt")
        write_mitsuba_curves(strands, curves)
        c = CAMERA
        direction = np.array(KEY_DIRECTION) / np.linalg.norm(KEY_DIRECTION)
        self.scene = mi.load_dict(
            {
                "type": "scene",
                "integrator": {"type": "path", "max_depth": MAX_BOUNCES + 1, "rr_depth": 3},
                "sensor": {
                    "type": "perspective",
                    "fov": c["fov"],
                    "fov_axis": "y",
                    "to_world": mi.ScalarTransform4f().look_at(
                        origin=c["position"], target=c["target"], up=[0, 1, 0]
                    ),
                    "sampler": {"type": "independent"},
                    "film": {
                        "type": "hdrfilm",
                        "width": width,
                        "height": height,
                        "rfilter": {"type": "box"},
                        "pixel_format": "rgb",
                    },
                },
                "key": {"type": "directional", "direction": (-direction).tolist(), "irradiance": KEY_IRRADIANCE},
                "dome": {"type": "constant", "radiance": DOME_RADIANCE},
                "hair": {
                    "type": "bsplinecurve",
                    "filename": curves,
                    "bsdf": {
                        "type": "hair",
                        "eumelanin": EUMELANIN,
                        "pheomelanin": PHEOMELANIN,
                        "longitudinal_roughness": BETA_M,
                        "azimuthal_roughness": BETA_N,
                        "scale_tilt": ALPHA_DEGREES,
                        "int_ior": 1.55,
                    },
                },
            }
        )
        self.compiled = set()

    def render(self, spp, seed, aov=False):
        import drjit as dr
        import mitsuba as mi

        if spp not in self.compiled:  # the first render of a kernel compiles it: not timed
            dr.eval(mi.render(self.scene, spp=spp, seed=10_000 + seed))
            self.compiled.add(spp)
        start = time.perf_counter()
        image = mi.render(self.scene, spp=spp, seed=seed)
        pixels = np.array(image, dtype=np.float64)
        seconds = time.perf_counter() - start
        return pixels[..., :3], None, seconds


class Cycles:
    name = "Cycles (Principled Hair, Chiang)"

    def __init__(self, python, strands, out, width, height):
        self.out = out
        curves = os.path.join(out, "groom_cycles.npz")
        np.savez(
            curves,
            counts=np.array([len(p) for p, _ in strands]),
            points=np.concatenate([p for p, _ in strands]).astype(np.float64),
            radii=np.concatenate([r for _, r in strands]).astype(np.float64),
        )
        shot = {
            "curves": curves,
            "camera_position": CAMERA["position"],
            "camera_target": CAMERA["target"],
            "fov": CAMERA["fov"],
            "key_direction": KEY_DIRECTION,
            "key_irradiance": KEY_IRRADIANCE,
            "key_angle_degrees": KEY_ANGLE_DEGREES,
            "dome_radiance": DOME_RADIANCE,
            "sigma_a": (EUMELANIN * EUMELANIN_SIGMA_A + PHEOMELANIN * PHEOMELANIN_SIGMA_A).tolist(),
            "beta_m": BETA_M,
            "beta_n": BETA_N,
            "alpha_degrees": ALPHA_DEGREES,
            "ior": HAIR_IOR,
            "max_bounces": MAX_BOUNCES,
            "width": width,
            "height": height,
            "threads": 2,
        }
        path = os.path.join(out, "shot_cycles.json")
        with open(path, "w") as f:
            json.dump(shot, f)
        worker = os.path.join(os.path.dirname(os.path.abspath(__file__)), "bench_peers_cycles.py")
        self.process = subprocess.Popen(
            [python, worker, path], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
        )

    def render(self, spp, seed, aov=False):
        import mitsuba as mi

        path = os.path.join(self.out, f"cycles_{spp}_{seed}.exr")
        self.process.stdin.write(f"{spp} {seed} {path}\n")
        self.process.stdin.flush()
        for line in self.process.stdout:
            if line.startswith("bench-peers-cycles "):
                seconds = json.loads(line.split(" ", 1)[1])["seconds"]
                break
        else:
            raise RuntimeError(f"the Cycles worker stopped (exit {self.process.wait()})")
        pixels = np.array(mi.Bitmap(path), dtype=np.float64)
        os.remove(path)
        return pixels[..., :3], None, float(seconds)


def measure(renderers, window, spps, runs):
    """Median time and errors per renderer and sample count. The renderers take turns on every
    seed, so a change of the machine's load hits both alike."""
    rows = {r.name: [] for r, _ in renderers}
    for spp in spps:
        samples = {r.name: ([], [], []) for r, _ in renderers}
        for seed in range(1, runs + 1):
            for renderer, reference in renderers:
                image, _, seconds = renderer.render(spp, seed)
                full, in_window, times = samples[renderer.name]
                full.append(relative_rmse(image, reference))
                in_window.append(relative_rmse(image, reference, window))
                times.append(seconds)
        for renderer, _ in renderers:
            full, in_window, times = samples[renderer.name]
            row = {
                "spp": spp,
                "seconds": float(np.median(times)),
                "rrmse_full": float(np.median(full)),
                "rrmse_window": float(np.median(in_window)),
                "load": load()[0],
            }
            rows[renderer.name].append(row)
            print(
                f"  {renderer.name:32s} {spp:5d} spp  {row['seconds']:8.3f} s  rRMSE full {row['rrmse_full']:.4f}"
                f"  window {row['rrmse_window']:.4f}  (load {row['load']:.1f})",
                flush=True,
            )
    return rows


def time_to_error(rows, key, target):
    """(c / target)^2 x seconds per spp, c and the cost as medians over the sample counts."""
    c = float(np.median([r[key] * math.sqrt(r["spp"]) for r in rows]))
    per_spp = float(np.median([r["seconds"] / r["spp"] for r in rows]))
    return (c / target) ** 2 * per_spp, c, per_spp


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--coif", default="target/release/coif")
    parser.add_argument("--out", default="out/bench-peers")
    parser.add_argument("--strands", type=int, default=20000)
    parser.add_argument("--res", default="200x150")
    parser.add_argument("--reference-spp", type=int, default=1024)
    parser.add_argument("--spps", default="4,8,16,32")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--target-spp", type=int, default=16)
    parser.add_argument(
        "--cycles-python",
        default=".deps/bpy-venv/bin/python",
        help="a Python with bpy (scripts/check_blender_setup.sh); 'none' leaves Cycles out",
    )
    args = parser.parse_args()
    width, height = (int(v) for v in args.res.split("x"))
    spps = [int(v) for v in args.spps.split(",")]
    os.makedirs(args.out, exist_ok=True)

    groom = os.path.join(args.out, "groom.hair")
    subprocess.run(
        [args.coif, "generate", "-o", groom, "--strands", str(args.strands), "--vertices", "24",
         "--style", "wavy", "--width", "0.00015", "--seed", "7"],
        check=True, capture_output=True,
    )  # fmt: skip
    strands = read_hair(groom)
    curves = os.path.join(args.out, "groom_bspline.usda")
    write_usda_bspline(strands, curves)
    print(
        f"groom: {len(strands)} B-spline strands x 24 control points, 150 um; {width}x{height}; {MAX_BOUNCES} bounces;"
        f" 2 threads; references {args.reference_spp} spp; {args.runs} seeds per count; load {load()}",
        flush=True,
    )

    coif = Coif(args.coif, curves, args.out, width, height)
    peers = [Mitsuba(strands, args.out, width, height)]
    if args.cycles_python != "none":
        peers.append(Cycles(args.cycles_python, strands, args.out, width, height))
    coif_reference, coverage, coif_reference_seconds = coif.render(args.reference_spp, 0)
    # The densest quarter of the pixels the hair covers (thin strands rarely cover a pixel whole).
    covered = coverage[coverage > 0.0]
    window = coverage >= np.quantile(covered, 0.75)
    print(f"dense-hair window: {int(window.sum())} of {width * height} pixels", flush=True)
    references = [(coif, coif_reference)]
    for peer in peers:
        started = time.perf_counter()
        reference, _, _ = peer.render(args.reference_spp, 0)
        references.append((peer, reference))
        print(
            f"reference {peer.name}: {time.perf_counter() - started:.1f} s; mean luminance in the window"
            f" {luminance(reference)[window].mean():.4f} (coif {luminance(coif_reference)[window].mean():.4f}),"
            f" full frame {luminance(reference).mean():.4f} (coif {luminance(coif_reference).mean():.4f})",
            flush=True,
        )
        np.save(os.path.join(args.out, f"{peer.name.split()[0].lower()}_reference.npy"), reference)
    print(f"reference coif: {coif_reference_seconds:.1f} s", flush=True)
    np.save(os.path.join(args.out, "coif_reference.npy"), coif_reference)

    results = measure(references, window, spps, args.runs)

    coif_rows = results[coif.name]
    summary = {}
    for key in ["rrmse_full", "rrmse_window"]:
        target_row = min(coif_rows, key=lambda r: abs(r["spp"] - args.target_spp))
        target = target_row[key]
        times = {name: time_to_error(rows, key, target) for name, rows in results.items()}
        coif_time = times[coif.name][0]
        print(f"time to coif's {target_row['spp']}-spp {key} ({target:.4f}):")
        for name, (seconds, c, per_spp) in times.items():
            print(f"  {name:32s} {seconds:8.3f} s  (c {c:.3f}, {per_spp:.4f} s/spp)  x{seconds / coif_time:.2f}")
        fastest = min((t[0], name) for name, t in times.items() if name != coif.name)
        print(f"  fastest peer {fastest[1]}: coif is {fastest[0] / coif_time:.2f}x as fast (target 3)")
        summary[key] = {name: t[0] for name, t in times.items()}
    with open(os.path.join(args.out, "bench_peers.json"), "w") as f:
        json.dump({"rows": results, "time_to_equal_noise": summary, "load": load()}, f, indent=1)


if __name__ == "__main__":
    main()
