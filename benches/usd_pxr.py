"""The pure-pxr side of `cargo bench --bench usd`: writes and reads the same groom as .usdc.

  usd_pxr.py write RAW_DIR OUT.usdc    RAW_DIR holds points.f32, widths.f32, counts.i32, ids.i32
                                       and attributes.json naming NAME.f32 primvars
  usd_pxr.py read STAGE.usdc

Prints one JSON object: seconds of the timed part, peak resident memory (VmHWM) and the resident
memory before any groom data existed (interpreter and libraries), in kB.
"""
import array
import json
import os
import sys
import time


def cpu_seconds():
    times = os.times()
    return times.user + times.system


def status_kb(field):
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    return 0


def load(folder, name, code):
    values = array.array(code)
    with open(f"{folder}/{name}", "rb") as f:
        values.frombytes(f.read())
    return values


def main():
    from pxr import Sdf, Usd, UsdGeom, Vt

    baseline = status_kb("VmRSS")
    command = sys.argv[1]
    if command == "write":
        folder, out = sys.argv[2], sys.argv[3]
        points, widths = load(folder, "points.f32", "f"), load(folder, "widths.f32", "f")
        counts, ids = load(folder, "counts.i32", "i"), load(folder, "ids.i32", "i")
        with open(f"{folder}/attributes.json") as f:
            attributes = [(a, load(folder, a["name"] + ".f32", "f")) for a in json.load(f)]
        start, cpu_start = time.perf_counter(), cpu_seconds()
        stage = Usd.Stage.CreateNew(out)
        UsdGeom.SetStageMetersPerUnit(stage, 1.0)
        UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
        groom = UsdGeom.Xform.Define(stage, "/Groom")
        stage.SetDefaultPrim(groom.GetPrim())
        curves = UsdGeom.BasisCurves.Define(stage, "/Groom/Strands")
        curves.CreateTypeAttr(UsdGeom.Tokens.linear)
        curves.CreateWrapAttr(UsdGeom.Tokens.nonperiodic)
        curves.CreateCurveVertexCountsAttr(Vt.IntArray.FromBuffer(counts))
        vt_points = Vt.Vec3fArray.FromBuffer(points)
        curves.CreatePointsAttr(vt_points)
        vt_widths = Vt.FloatArray.FromBuffer(widths)
        curves.CreateWidthsAttr(vt_widths)
        curves.SetWidthsInterpolation(UsdGeom.Tokens.vertex)
        curves.CreateExtentAttr(UsdGeom.Curves.ComputeExtent(vt_points, vt_widths))
        ids_primvar = UsdGeom.PrimvarsAPI(curves).CreatePrimvar(
            "groom_id", Sdf.ValueTypeNames.IntArray, UsdGeom.Tokens.uniform
        )
        ids_primvar.Set(Vt.IntArray.FromBuffer(ids))
        for attribute, values in attributes:
            primvar = UsdGeom.PrimvarsAPI(curves).CreatePrimvar(
                attribute["name"], Sdf.ValueTypeNames.Find(attribute["type"]), attribute["interpolation"]
            )
            array_type = Vt.FloatArray if attribute["type"] == "float[]" else Vt.Vec3fArray
            primvar.Set(array_type.FromBuffer(values))
        stage.GetRootLayer().Save()
        seconds = time.perf_counter() - start
    else:
        path = sys.argv[2]
        start, cpu_start = time.perf_counter(), cpu_seconds()
        stage = Usd.Stage.Open(path)
        curves = UsdGeom.BasisCurves(stage.GetPrimAtPath("/Groom/Strands"))
        # Copy every array out of the (memory-mapped) file, as a reader building a groom must.
        data = [
            bytes(memoryview(curves.GetCurveVertexCountsAttr().Get())),
            bytes(memoryview(curves.GetPointsAttr().Get())),
            bytes(memoryview(curves.GetWidthsAttr().Get())),
        ]
        data += [bytes(memoryview(p.Get())) for p in UsdGeom.PrimvarsAPI(curves).GetAuthoredPrimvars()]
        seconds = time.perf_counter() - start
        assert sum(len(d) for d in data) > 0
    cpu = cpu_seconds() - cpu_start
    print(json.dumps({"seconds": seconds, "cpu_seconds": cpu, "peak_kb": status_kb("VmHWM"), "baseline_kb": baseline}))


if __name__ == "__main__":
    main()
