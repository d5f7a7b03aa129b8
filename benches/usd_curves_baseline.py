"""usd-core baseline for `cargo bench --bench alembic`: writes and reads the same curves as
.usdc (static, and one time sample per frame) and prints the seconds each step took.

Usage: python usd_curves_baseline.py DIR FRAMES
DIR holds points.f32 (x y z per vertex), widths.f32 and counts.i32 written by the benchmark.
Frame f's points are the base points plus f * (0.001, 0, 0), as in the Rust benchmark.
"""
import array
import os
import sys
import time

from pxr import Gf, Usd, UsdGeom, Vt


def load(path, code):
    data = array.array(code)
    with open(path, "rb") as f:
        data.frombytes(f.read())
    return data


def main():
    folder, frames = sys.argv[1], int(sys.argv[2])
    points_raw = load(os.path.join(folder, "points.f32"), "f")
    base = Vt.Vec3fArray.FromBuffer(memoryview(points_raw).cast("B").cast("f", [len(points_raw) // 3, 3]))
    widths = Vt.FloatArray.FromBuffer(load(os.path.join(folder, "widths.f32"), "f"))
    counts = Vt.IntArray.FromBuffer(load(os.path.join(folder, "counts.i32"), "i"))
    step = Vt.Vec3fArray(len(base), Gf.Vec3f(0.001, 0.0, 0.0))
    animated = frames > 1
    # Frame data is made before the clock starts, as in the Rust benchmark.
    frame_points = [base + step * float(f) for f in range(frames)] if animated else [base]
    path = os.path.join(folder, "baseline.usdc")

    start = time.perf_counter()
    stage = Usd.Stage.CreateNew(path)
    curves = UsdGeom.BasisCurves.Define(stage, "/groom/curves")
    curves.CreateTypeAttr(UsdGeom.Tokens.linear)
    curves.CreateCurveVertexCountsAttr(counts)
    curves.CreateWidthsAttr(widths)
    curves.SetWidthsInterpolation(UsdGeom.Tokens.vertex)
    points = curves.CreatePointsAttr()
    if animated:
        stage.SetStartTimeCode(1)
        stage.SetEndTimeCode(frames)
        for f, p in enumerate(frame_points):
            points.Set(p, Usd.TimeCode(f + 1))
    else:
        points.Set(base)
    stage.GetRootLayer().Save()
    del points, curves, stage
    write_s = time.perf_counter() - start

    start = time.perf_counter()
    stage = Usd.Stage.Open(path)
    curves = UsdGeom.BasisCurves(stage.GetPrimAtPath("/groom/curves"))
    total = 0
    points = curves.GetPointsAttr()
    times = [Usd.TimeCode(f + 1) for f in range(frames)] if animated else [Usd.TimeCode.Default()]
    # usdc hands out arrays backed by the memory-mapped file; writing one element detaches the
    # array, copying it into owned memory, as coif's reader produces owned arrays.
    arrays = [curves.GetCurveVertexCountsAttr().Get(), curves.GetWidthsAttr().Get()]
    arrays += [points.Get(t) for t in times]
    for a in arrays:
        a[0] = a[0]
        total += len(a)
    read_s = time.perf_counter() - start
    print(f"write_s={write_s:.6f} read_s={read_s:.6f} values={total} bytes={os.path.getsize(path)}")


if __name__ == "__main__":
    main()
